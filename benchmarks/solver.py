#!/usr/bin/env python3
"""Solver benchmark: solver-demo against CalculiX and scikit-fem + pyamg on one problem.

The MNI152 T1 template (from the installed nilearn package) is resampled to about 2.5 mm
(scipy zoom, linear), meshed by tptd-mesh as {T1 >= 151.9} (grey + white matter, ~1.1 M tets),
and -div(k grad u) = s with k = 1, s = 1, u = 0 on the boundary group `alpha` is solved by
  * solver-demo (this repository; .msh input; Jacobi PCG, relative residual --tol),
  * CalculiX ccx (the same mesh exported as .inp; *HEAT TRANSFER, STEADY STATE; its default
    direct solver),
  * scikit-fem + pyamg (benchmarks/skfem_peer.py; P1 assembly, smoothed-aggregation AMG + CG
    at the same relative tolerance).
Each runs in a fresh process; the stage times are the tools' own (solver-demo prints them,
the Python peer times its stages with perf_counter); ccx prints none, so its whole wall time
is reported. The three solutions are compared node by node.

  python3 benchmarks/solver.py                # writes benchmarks/solver_results.{md,json}
  python3 benchmarks/solver.py --spacing 4    # smaller and faster (~0.3 M tets)

Needs: pip install numpy scipy nibabel nilearn meshio scikit-fem pyamg vtk matplotlib;
apt-get install calculix-ccx; cargo build --release. Outputs go to benchmarks/out/solver/
(git-ignored), including u.vtu for ParaView and the picture benchmarks/solver_slice.png.
"""
import argparse
import json
import os
import platform
import re
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
DATA = os.path.join(HERE, "data")
OUT = os.path.join(HERE, "out", "solver")
BIN = os.path.join(REPO, "target", "release")


def machine():
    cpu = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
        mem = int(open("/proc/meminfo").readline().split()[1]) / 2**20
    except OSError:
        mem = 0
    return f"{os.cpu_count()} cores, {cpu}, {mem:.0f} GiB, {platform.system()}"


def run(cmd, cwd=None, env=None):
    """Runs cmd; returns (wall seconds, stdout). Exits on failure."""
    t = time.perf_counter()
    p = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if p.returncode != 0:
        sys.exit(f"failed: {' '.join(cmd)}\n{p.stdout}\n{p.stderr}")
    return wall, p.stdout


def volume(spacing):
    """The resampled T1 as .npy; returns (path, per-axis spacing in mm)."""
    import nibabel
    import nilearn
    import scipy.ndimage
    src = os.path.join(os.path.dirname(nilearn.__file__), "datasets", "data",
                       "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz")
    v = np.asarray(nibabel.load(src).get_fdata(), dtype=np.float64)
    z = scipy.ndimage.zoom(v, 1.0 / spacing, order=1)
    # zoom maps the corner samples onto each other
    h = [(a - 1) / (b - 1) for a, b in zip(v.shape, z.shape)]
    path = os.path.join(DATA, f"mni_t1_{spacing}mm.npy")
    np.save(path, z)
    return path, h


def ours(mesh, args, threads=None):
    out = os.path.join(OUT, "u.vtu")
    cmd = [os.path.join(BIN, "solver-demo"), mesh, "-o", out, "--k", str(args.k),
           "--source", str(args.source), "--dirichlet", "alpha=0", "--tol", str(args.tol)]
    if threads:
        cmd += ["-j", str(threads)]
    wall, text = run(cmd)
    times = dict((n, float(s)) for n, s in re.findall(r"(\w+) ([0-9.]+)", text.split("times (s):")[1]))
    it = int(re.search(r"iterations: (\d+)", text).group(1))
    res = float(re.search(r"final relative residual: (\S+)", text).group(1))
    unknowns = int(re.search(r"unknowns: (\d+)", text).group(1))
    return {"wall_s": wall, "read_s": times["read"], "assemble_s": times["assemble"],
            "solve_s": times["solve"], "setup_s": times["setup"], "iterations": it,
            "residual": res, "unknowns": unknowns, "stdout": text, "u": read_vtu_u(out)}


def read_vtu_u(path):
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    return vtk_to_numpy(r.GetOutput().GetPointData().GetArray("u")).copy()


def calculix(inp, args, n_nodes):
    deck = (f"*INCLUDE, INPUT={os.path.basename(inp)}\n*MATERIAL, NAME=M\n*CONDUCTIVITY\n{args.k}\n"
            "*SOLID SECTION, ELSET=DOMAIN, MATERIAL=M\n*STEP\n*HEAT TRANSFER, STEADY STATE\n"
            "*BOUNDARY\nALPHA, 11, 11, 0.0\n"
            f"*DFLUX\nDOMAIN, BF, {args.source}\n*NODE FILE\nNT\n*END STEP\n")
    with open(os.path.join(OUT, "job.inp"), "w") as f:
        f.write(deck)
    env = dict(os.environ, OMP_NUM_THREADS=str(os.cpu_count()))
    wall, text = run(["ccx", "-i", "job"], cwd=OUT, env=env)
    u = np.zeros(n_nodes)
    with open(os.path.join(OUT, "job.frd")) as f:
        block = False
        for line in f:
            if "NDTEMP" in line:
                block = True
            elif block and line.startswith(" -3"):
                break
            elif block and line.startswith(" -1"):
                u[int(line[3:13]) - 1] = float(line[13:25])
    return {"wall_s": wall, "u": u}


def skfem_peer(mesh, args):
    upath = os.path.join(OUT, "u_skfem.npy")
    wall, text = run([sys.executable, os.path.join(HERE, "skfem_peer.py"), mesh, "--k", str(args.k),
                      "--source", str(args.source), "--tol", str(args.tol), "--out", upath])
    r = json.loads(text.strip().splitlines()[-1])
    r["wall_s"] = wall
    r["u"] = np.load(upath)
    return r


def picture(path):
    """A mid-sagittal-ish slice of u (VTK cut, matplotlib), small PNG."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(os.path.join(OUT, "u.vtu"))
    r.Update()
    g = r.GetOutput()
    b = g.GetBounds()
    plane = vtk.vtkPlane()
    plane.SetOrigin(0.5 * (b[0] + b[1]) + 12.0, 0, 0)  # 12 mm off the midline: a hemisphere
    plane.SetNormal(1, 0, 0)
    cut = vtk.vtkCutter()
    cut.SetCutFunction(plane)
    cut.SetInputData(g)
    tri = vtk.vtkTriangleFilter()
    tri.SetInputConnection(cut.GetOutputPort())
    tri.Update()
    s = tri.GetOutput()
    pts = vtk_to_numpy(s.GetPoints().GetData())
    cells = vtk_to_numpy(s.GetPolys().GetConnectivityArray()).reshape(-1, 3)
    u = vtk_to_numpy(s.GetPointData().GetArray("u"))
    fig, ax = plt.subplots(figsize=(5.2, 4.2), dpi=90)
    tp = ax.tripcolor(pts[:, 1], pts[:, 2], cells, u, shading="gouraud", cmap="inferno")
    ax.set_aspect("equal")
    ax.set_xlabel("y (mm)")
    ax.set_ylabel("z (mm)")
    ax.set_title("u on a sagittal cut, -Δu = 1 in {T1 ≥ 151.9}, u = 0 on its surface", fontsize=8)
    fig.colorbar(tp, ax=ax, shrink=0.8, label="u")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def report(res, args, meta):
    o, o1, c, s = res["ours"], res["ours_j1"], res.get("ccx"), res.get("skfem")
    ours_as = o["assemble_s"] + o["solve_s"]
    lines = [
        "# Solver benchmark (generated by `python3 benchmarks/solver.py`)",
        "",
        f"Machine: {meta['machine']}. {meta['date']}.",
        "",
        f"Problem: -div(k grad u) = s, k = {args.k}, s = {args.source}, u = 0 on `alpha`, on "
        f"`tptd-mesh` {meta['volume']} --alpha {args.alpha} (MNI152 T1 resampled to "
        f"{args.spacing} mm): {meta['nodes']:,} nodes, {meta['tets']:,} tets, "
        f"{o['unknowns']:,} unknowns; relative residual tolerance {args.tol:g}.",
        "",
        "| solver | assembly s | solve s | assembly + solve s | whole process s | iterations | max. nodal difference to ccx (relative) |",
        "|---|---|---|---|---|---|---|",
        f"| solver-demo (Jacobi PCG, {os.cpu_count()} threads) | {o['assemble_s']:.2f} | {o['solve_s']:.2f} | **{ours_as:.2f}** | "
        f"{o['wall_s']:.2f} | {o['iterations']} | {res.get('diff_ours', float('nan')):.1e} |",
        f"| solver-demo -j 1 | {o1['assemble_s']:.2f} | {o1['solve_s']:.2f} | {o1['assemble_s'] + o1['solve_s']:.2f} | "
        f"{o1['wall_s']:.2f} | {o1['iterations']} | same |",
    ]
    if s:
        lines.append(
            f"| scikit-fem {meta['skfem']} + pyamg {meta['pyamg']} (SA-AMG + CG) | {s['assemble_s']:.2f} | "
            f"{s['solve_s']:.2f} | {s['assemble_s'] + s['solve_s']:.2f} | {s['wall_s']:.2f} | "
            f"{s['iterations']} | {res.get('diff_skfem', float('nan')):.1e} |")
    if c:
        lines.append(f"| CalculiX {meta['ccx']} (ccx, default direct solver, OMP {os.cpu_count()}) | – | – | "
                     f"≤ {c['wall_s']:.2f} (whole run) | {c['wall_s']:.2f} | direct | 0 |")
    lines.append("")
    if s:
        lines.append(f"solver-demo / scikit-fem+pyamg, assembly + solve: {(s['assemble_s'] + s['solve_s']) / ours_as:.1f}× faster.")
    if c:
        lines.append(f"solver-demo assembly + solve vs the whole ccx run: {c['wall_s'] / ours_as:.1f}× faster; "
                     f"whole process vs whole process: {c['wall_s'] / o['wall_s']:.1f}×.")
    lines.append("")
    lines.append("The whole-process times include reading the mesh text (and, for solver-demo, writing the .vtu).")
    lines.append(f"solver-demo: median of {args.reps} runs per thread count (by assembly + solve); the peers run once.")
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spacing", type=float, default=2.5, help="resampled voxel size in mm")
    ap.add_argument("--alpha", type=float, default=151.9)
    ap.add_argument("--k", type=float, default=1.0)
    ap.add_argument("--source", type=float, default=1.0)
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--reps", type=int, default=3,
                    help="solver-demo runs per thread count (the median is reported); peers run once")
    ap.add_argument("--no-ccx", action="store_true")
    ap.add_argument("--no-skfem", action="store_true")
    ap.add_argument("--out", default=os.path.join(HERE, "solver_results"), help="results prefix")
    args = ap.parse_args()
    os.makedirs(OUT, exist_ok=True)
    os.makedirs(DATA, exist_ok=True)

    npy, h = volume(args.spacing)
    msh, inp = os.path.join(OUT, "brain.msh"), os.path.join(OUT, "brain.inp")
    sp = ",".join(f"{x:.6f}" for x in h)
    for path in (msh, inp):
        _, text = run([os.path.join(BIN, "tptd-mesh"), npy, "--alpha", str(args.alpha), "--spacing", sp, "-o", path])
    m = re.search(r"mesh\s+(\d+) nodes, (\d+) tets", text)
    import pyamg
    import skfem
    meta = {"machine": machine(), "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            "nodes": int(m.group(1)), "tets": int(m.group(2)), "volume": os.path.relpath(npy, REPO),
            "spacing_mm": h, "skfem": skfem.__version__, "pyamg": pyamg.__version__,
            "ccx": "2.20"}
    print(f"mesh: {meta['nodes']} nodes, {meta['tets']} tets", flush=True)

    def median_of(threads):
        runs = sorted((ours(msh, args, threads) for _ in range(args.reps)),
                      key=lambda r: r["assemble_s"] + r["solve_s"])
        return runs[len(runs) // 2]
    res = {"ours_j1": median_of(1), "ours": median_of(None)}
    print(res["ours_j1"]["stdout"], res["ours"]["stdout"], flush=True)
    if not args.no_skfem:
        res["skfem"] = skfem_peer(msh, args)
        print("skfem+pyamg:", {k: v for k, v in res["skfem"].items() if k != "u"}, flush=True)
    if not args.no_ccx:
        res["ccx"] = calculix(inp, args, meta["nodes"])
        print(f"ccx: {res['ccx']['wall_s']:.2f} s", flush=True)
        ref = res["ccx"]["u"]
        scale = np.abs(ref).max()
        res["diff_ours"] = float(np.abs(res["ours"]["u"] - ref).max() / scale)
        if "skfem" in res:
            res["diff_skfem"] = float(np.abs(res["skfem"]["u"] - ref).max() / scale)
    md = report(res, args, meta)
    print(md)
    picture(os.path.join(HERE, "solver_slice.png"))
    clean = {k: ({kk: vv for kk, vv in v.items() if kk not in ("u", "stdout")} if isinstance(v, dict) else v)
             for k, v in res.items()}
    with open(args.out + ".json", "w") as f:
        json.dump({"meta": meta, "args": vars(args), "results": clean}, f, indent=1)
    with open(args.out + ".md", "w") as f:
        f.write(md)


if __name__ == "__main__":
    main()
