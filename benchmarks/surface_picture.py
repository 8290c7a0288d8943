#!/usr/bin/env python3
"""The README's isosurface picture: the demo volume's level set f = 0.5 from `ctd` (correct)
and `six` (the usual 6-fold split) side by side, seen along the two vessels.

usage: python3 benchmarks/surface_picture.py [--bin target/release/tptd-mesh]
Writes benchmarks/out/demo_{ctd,six}.obj and .json (git-ignored) and
benchmarks/surface_ctd_vs_six.png. Needs numpy and matplotlib.
"""
import argparse
import json
import os
import subprocess

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))


def read_obj(path):
    v, f = [], []
    for line in open(path):
        if line.startswith("v "):
            v.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("f "):
            f.append([int(x) - 1 for x in line.split()[1:4]])
    return np.array(v), np.array(f)


def panel(ax, v, f, title):
    tri = v[f]
    cx = tri[:, :, 0].mean(axis=1)
    tri = tri[(cx > 17) & (cx < 23)]  # a slab across the vessels: the cut shows the gap
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True) + 1e-300
    light = np.array([0.6, -0.3, 0.75])
    light /= np.linalg.norm(light)
    shade = 0.25 + 0.75 * np.abs(n @ light)
    colors = plt.cm.viridis(0.35 + 0.5 * shade)
    ax.add_collection3d(Poly3DCollection(tri, facecolors=colors, edgecolors="none"))
    ax.set_xlim(17, 23)
    ax.set_ylim(4, 19)
    ax.set_zlim(4, 19)
    ax.set_box_aspect((6, 15, 15))
    ax.view_init(elev=8, azim=-8)
    ax.set_axis_off()
    ax.set_title(title, fontsize=10)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default=os.path.join(HERE, "..", "target", "release", "tptd-mesh"))
    args = ap.parse_args()
    out = os.path.join(HERE, "out")
    os.makedirs(out, exist_ok=True)
    fig = plt.figure(figsize=(8, 4.2), dpi=80)
    for k, method in enumerate(["ctd", "six"]):
        obj = os.path.join(out, f"demo_{method}.obj")
        rep = os.path.join(out, f"demo_{method}.json")
        subprocess.run([args.bin, "--demo", "-q", "--method", method, "-o", obj, "--report", rep],
                       check=True)
        s = json.load(open(rep))["surface"]
        v, f = read_obj(obj)
        b = s["betti"]
        name = "tptd / ctd (trilinear topology)" if method == "ctd" else "six (usual 6-fold split)"
        title = f"{name}\n{b[0]} surface{'s' if b[0] != 1 else ''}, Betti {b}"
        panel(fig.add_subplot(1, 2, k + 1, projection="3d"), v, f, title)
        print(f"{method}: {s['vertices']} vertices, {s['triangles']} triangles, Betti {b}")
    fig.suptitle("Demo volume, level set f = 0.5: two vessels 1/3 voxel apart (slab 17 < x < 23)",
                 fontsize=10)
    png = os.path.join(HERE, "surface_ctd_vs_six.png")
    fig.savefig(png, dpi=80)
    print(f"wrote {png} ({os.path.getsize(png) // 1024} kB)")


main()
