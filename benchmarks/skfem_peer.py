#!/usr/bin/env python3
"""scikit-fem + pyamg peer of benchmarks/solver.py: the same P1 problem
-div(k grad u) = s, u = 0 on the nodes of the boundary group `alpha`, on a .msh written by
tptd-mesh. Prints one JSON line with the stage times; saves u (nodal, mesh order) as .npy.

  python3 benchmarks/skfem_peer.py MESH.msh --k 1 --source 1 --tol 1e-8 --out u.npy
"""
import argparse
import json
import time

import meshio
import numpy as np
import pyamg
import skfem
from skfem.models.poisson import laplace, unit_load


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("--k", type=float, default=1.0)
    ap.add_argument("--source", type=float, default=1.0)
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--out")
    a = ap.parse_args()

    t = time.perf_counter()
    m = meshio.read(a.mesh)
    tets = m.cells_dict["tetra"]
    alpha_tag = 1  # tptd-mesh's physical tag of the group `alpha`
    tri_nodes = [
        c.data[m.cell_data["gmsh:physical"][i] == alpha_tag]
        for i, c in enumerate(m.cells) if c.type == "triangle"
    ]
    fixed = np.unique(np.concatenate(tri_nodes))
    t_read = time.perf_counter() - t

    t = time.perf_counter()
    mesh = skfem.MeshTet(np.ascontiguousarray(m.points.T), np.ascontiguousarray(tets.T))
    basis = skfem.Basis(mesh, skfem.ElementTetP1())
    A = a.k * laplace.assemble(basis)
    b = a.source * unit_load.assemble(basis)
    Aff, bf, _, free = skfem.condense(A, b, D=fixed)
    Aff = Aff.tocsr()
    t_assemble = time.perf_counter() - t

    t = time.perf_counter()
    ml = pyamg.smoothed_aggregation_solver(Aff)
    res = []
    xf = ml.solve(bf, tol=a.tol, accel="cg", residuals=res, maxiter=1000)
    t_solve = time.perf_counter() - t

    u = np.zeros(len(m.points))
    u[free] = xf
    rel = np.linalg.norm(bf - Aff @ xf) / np.linalg.norm(bf)
    if a.out:
        np.save(a.out, u)
    print(json.dumps({
        "read_s": t_read, "assemble_s": t_assemble, "solve_s": t_solve,
        "unknowns": int(len(free)), "iterations": len(res) - 1, "residual": float(rel),
    }))


if __name__ == "__main__":
    main()
