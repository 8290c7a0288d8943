#!/usr/bin/env python3
"""Round-trip checker for tptd's mesh writers (called by tests/write_formats.rs).

usage: check_mesh.py READER FORMAT FILE EXPECTED_JSON
  READER  meshio | vtk
  FORMAT  msh41 | msh22 | inp | vtu
EXPECTED_JSON holds {"points": [[x,y,z],...], "values": [...], "tets": [[a,b,c,d],...],
"boundary": {"alpha": [[a,b,c],...], ...}} with 0-based indices (only labels that occur).
Optional keys (meshio reader): "coord_rtol" (relative tolerance of the .inp coordinates,
default 1e-11) and "positive_volumes" (true: every tet, as read, must have a positive volume
computed by numpy from the points and connectivity meshio returned).
Prints "OK ..." and exits 0 on success; prints the failures and exits 1 otherwise.
"""
import json
import sys

import numpy as np

errors = []


def check(cond, msg):
    if not cond:
        errors.append(msg)


def same_floats(a, b, exact, rtol=1e-11):
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.shape != b.shape:
        return False
    if exact:
        return bool(np.array_equal(a, b))
    return bool(np.allclose(a, b, rtol=rtol, atol=1e-300))


def check_meshio(fmt, path, exp):
    import meshio

    file_format = {"msh41": "gmsh", "msh22": "gmsh", "inp": "abaqus", "vtu": "vtu"}[fmt]
    m = meshio.read(path, file_format=file_format)
    pts = np.asarray(exp["points"], dtype=float)
    tets = np.asarray(exp["tets"], dtype=np.int64).reshape(-1, 4)
    check(m.points.shape == pts.shape, f"points shape {m.points.shape} != {pts.shape}")
    check(
        same_floats(m.points, pts, exact=(fmt != "inp"), rtol=exp.get("coord_rtol", 1e-11)),
        "coordinates differ",
    )
    tet_blocks = [c.data for c in m.cells if c.type == "tetra"]
    got_tets = np.concatenate(tet_blocks) if tet_blocks else np.zeros((0, 4), np.int64)
    check(got_tets.shape == tets.shape, f"tet count {got_tets.shape} != {tets.shape}")
    check(np.array_equal(got_tets, tets), "tet connectivity differs")
    other = sorted({c.type for c in m.cells} - {"tetra", "triangle"})
    check(not other, f"unexpected cell types {other}")
    if exp.get("positive_volumes") and len(got_tets) and got_tets.max() < len(m.points):
        p = np.asarray(m.points, dtype=float)[got_tets]
        vol = np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])) / 6
        bad = np.flatnonzero(~(vol > 0))
        check(len(bad) == 0, f"{len(bad)} tets with non-positive volume, first {bad[:5].tolist()}: {vol[bad[:5]].tolist()}")

    if fmt != "inp":
        check("f" in m.point_data, f"no point data 'f' (have {list(m.point_data)})")
        if "f" in m.point_data:
            check(same_floats(np.ravel(m.point_data["f"]), exp["values"], exact=True), "point data 'f' differs")

    if fmt in ("msh41", "msh22"):
        tags = {"alpha": 1, "beta": 2, "box": 3}
        want_fd = {name: (tags[name], 2) for name in exp["boundary"]}
        want_fd["domain"] = (4, 3)
        got_fd = {k: (int(v[0]), int(v[1])) for k, v in m.field_data.items()}
        check(got_fd == want_fd, f"physical groups {got_fd} != {want_fd}")
        phys = m.cell_data.get("gmsh:physical")
        check(phys is not None, "no gmsh:physical cell data")
        if phys is not None:
            tris = {}
            for block, p in zip(m.cells, phys):
                if block.type == "tetra":
                    check(np.all(p == 4), "tets not in physical group 4 (domain)")
                elif block.type == "triangle":
                    for tri, tag in zip(block.data.tolist(), p.tolist()):
                        tris.setdefault(int(tag), []).append(tri)
            want = {tags[k]: v for k, v in exp["boundary"].items()}
            check(tris == want, "boundary triangles per physical group differ")
    elif fmt == "inp":
        check("DOMAIN" in m.cell_sets, f"no cell set DOMAIN (have {list(m.cell_sets)})")
        if "DOMAIN" in m.cell_sets:
            ids = np.concatenate([np.asarray(a).ravel() for a in m.cell_sets["DOMAIN"]])
            check(np.array_equal(np.sort(ids), np.arange(len(tets))), "DOMAIN is not all elements")
        want_sets = {k.upper(): sorted({v for tri in tris for v in tri}) for k, tris in exp["boundary"].items()}
        got_sets = {k: sorted(np.asarray(v).tolist()) for k, v in m.point_sets.items() if k != "NALL"}
        check(got_sets == want_sets, f"node sets differ: {sorted(got_sets)} vs {sorted(want_sets)}")
        if "NALL" in m.point_sets:
            check(len(m.point_sets["NALL"]) == len(pts), "NALL does not hold all nodes")
    return f"{len(m.points)} points, {len(got_tets)} tets"


def check_vtk(fmt, path, exp):
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy

    assert fmt == "vtu", "the vtk reader is only used for .vtu"
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    check(r.GetErrorCode() == 0, f"reader error code {r.GetErrorCode()}")
    g = r.GetOutput()
    pts = np.asarray(exp["points"], dtype=float)
    tets = np.asarray(exp["tets"], dtype=np.int64).reshape(-1, 4)
    check(g.GetNumberOfPoints() == len(pts), f"points {g.GetNumberOfPoints()} != {len(pts)}")
    check(g.GetNumberOfCells() == len(tets), f"cells {g.GetNumberOfCells()} != {len(tets)}")
    if g.GetNumberOfPoints() == len(pts) and len(pts):
        check(same_floats(vtk_to_numpy(g.GetPoints().GetData()), pts, exact=True), "coordinates differ")
    for c in range(g.GetNumberOfCells()):
        if g.GetCellType(c) != 10:
            check(False, f"cell {c} has type {g.GetCellType(c)}")
            break
        ids = g.GetCell(c).GetPointIds()
        got = [ids.GetId(k) for k in range(ids.GetNumberOfIds())]
        if got != tets[c].tolist():
            check(False, f"cell {c}: {got} != {tets[c].tolist()}")
            break
        # VTK's own volume must be positive for the tet ordering to be right
        p = [np.array(g.GetPoint(i)) for i in got]
        vol = np.dot(p[1] - p[0], np.cross(p[2] - p[0], p[3] - p[0])) / 6
        check(vol > 0, f"cell {c} has non-positive volume {vol}")
    f = g.GetPointData().GetArray("f")
    check(f is not None, "no point data 'f'")
    if f is not None:
        check(same_floats(vtk_to_numpy(f), exp["values"], exact=True), "point data 'f' differs")
    check(g.GetPointData().GetScalars() is not None, "'f' is not the active scalars")
    return f"{g.GetNumberOfPoints()} points, {g.GetNumberOfCells()} cells"


def main():
    if len(sys.argv) != 5:
        print(__doc__)
        return 2
    reader, fmt, path, exp_path = sys.argv[1:]
    with open(exp_path) as fh:
        exp = json.load(fh)
    summary = {"meshio": check_meshio, "vtk": check_vtk}[reader](fmt, path, exp)
    if errors:
        for e in errors:
            print(f"FAIL {reader} {fmt} {path}: {e}")
        return 1
    print(f"OK {reader} {fmt}: {summary}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
