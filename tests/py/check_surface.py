#!/usr/bin/env python3
"""Round-trip checker for tptd's isosurface writers (called by tests/surface.rs).

usage: check_surface.py FILE EXPECTED_JSON
FILE is .obj, .ply (binary or ASCII) or .stl (binary or ASCII), read with meshio.
EXPECTED_JSON holds {"points": [[x,y,z],...], "triangles": [[a,b,c],...], "labels": [0|1|2,...],
"area": A} with 0-based indices.
* OBJ and PLY: the same points (exactly; PLY also the labels: a face whose three vertices carry
  label L is on level L, any other face is a cap) and the same triangles in the same order;
  OBJ groups in label order.
* STL (no shared vertices, single precision in binary): the same triangle corners, in order,
  to float32 precision, and the same total area; normals (ASCII and binary) point the way of
  the right-hand rule.
Prints "OK ..." and exits 0 on success; prints the failures and exits 1 otherwise.
"""
import json
import sys

import meshio
import numpy as np

errors = []


def check(cond, msg):
    if not cond:
        errors.append(msg)


def triangles(mesh):
    blocks = [c for c in mesh.cells if c.type == "triangle"]
    check(len(blocks) == len(mesh.cells), f"non-triangle cells: {[c.type for c in mesh.cells]}")
    return np.concatenate([b.data for b in blocks]) if blocks else np.zeros((0, 3), int)


def area(points, tris):
    p = points[tris]
    return 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum()


def main():
    path, exp_path = sys.argv[1], sys.argv[2]
    exp = json.load(open(exp_path))
    pts = np.asarray(exp["points"], float)
    tris = np.asarray(exp["triangles"], int)
    labels = np.asarray(exp["labels"], int)
    mesh = meshio.read(path)
    got = triangles(mesh)
    ext = path.rsplit(".", 1)[-1].lower()
    if ext in ("obj", "ply"):
        check(np.array_equal(mesh.points, pts), "points differ")
        check(np.array_equal(got, tris), "triangles differ")
    if ext == "obj":
        groups = np.concatenate(mesh.cell_data["obj:group_ids"])
        # groups are numbered in order of appearance, triangles are grouped by label
        _, first = np.unique(labels, return_index=True)
        rank = np.searchsorted(np.sort(np.unique(labels)), labels)
        check(np.array_equal(groups - groups.min(), rank), "OBJ groups do not follow the labels")
    if ext == "ply":
        vl = np.asarray(mesh.point_data["label"]).astype(int)
        tl = vl[got]
        face = np.where((tl == tl[:, :1]).all(axis=1) & (tl[:, 0] < 2), tl[:, 0], 2)
        check(np.array_equal(face, labels), "PLY labels do not give the triangle labels")
    if ext == "stl":
        corners = mesh.points[got]
        want = pts[tris]
        check(corners.shape == want.shape, f"STL: {corners.shape} corners, want {want.shape}")
        if corners.shape == want.shape:
            err = np.abs(corners - want).max()
            check(err <= 1e-6 * max(1.0, np.abs(want).max()), f"STL corners off by {err}")
    a = area(mesh.points, got)
    check(abs(a - exp["area"]) <= 1e-5 * exp["area"], f"area {a}, expected {exp['area']}")
    if errors:
        print("\n".join(errors))
        sys.exit(1)
    print(f"OK {path.rsplit('/', 1)[-1]}: {len(mesh.points)} points, {len(got)} triangles, area {a:.6f}")


main()
