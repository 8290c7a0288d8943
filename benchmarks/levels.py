#!/usr/bin/env python3
"""Several regions in one run (`tptd-mesh --levels`) on the whole MNI152 2009a T1 (nilearn):
the cost per output tet of meshing three regions in one pass against meshing their union as
one interval, and the README's picture of the regions on an axial cut.

usage: python3 benchmarks/levels.py [--bin target/release/tptd-mesh] [--runs 3] [--no-picture | --picture-only]

Runs, alternating, `tptd-mesh T1 --levels L1,L2,L3,inf` and `tptd-mesh T1 --alpha L1` (the
union) with `--report`, `-j 2`; the mesh stage (`timings_seconds.mesh`, meshing with the
analysis, streamed to disk) per output tet, best of `--runs` each; writes
benchmarks/levels_results.md and benchmarks/levels_slice.png (from the .vtu of the
three-region run, its `region` cell data, cut at z = 10.37 mm, off the grid planes). Meshes go to benchmarks/out/
(git-ignored). Needs numpy, matplotlib, meshio and nilearn.
"""
import argparse
import json
import os
import platform
import subprocess

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
T1_NAME = "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz"
# Levels between integers and away from the critical values (tptd-mesh checks them and says
# nothing): dark (CSF and background edge), grey matter, white matter, by T1 intensity.
LEVELS = ["40.0213", "101.0137", "151.0135", "inf"]
NAMES = "csf,grey,white"
# The axial cut of the picture (mm): through the ventricles, between grid planes.
CUT_Z = 10.37


def t1_path():
    import nilearn

    return os.path.join(os.path.dirname(nilearn.__file__), "datasets", "data", T1_NAME)


def run(binary, args, out, report):
    cmd = [binary, t1_path(), *args, "-o", out, "--report", report, "-q", "-j", "2"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)}: {p.stderr.strip()}")
    return json.load(open(report))


def timing(binary, runs, out):
    levels = ["--levels", ",".join(LEVELS), "--region-names", NAMES]
    union = ["--alpha", LEVELS[0]]
    separate = [
        (f"region{k}", ["--alpha", LEVELS[k]] + (["--beta", LEVELS[k + 1]] if LEVELS[k + 1] != "inf" else []))
        for k in range(len(LEVELS) - 1)
    ]
    best = {}
    for _ in range(runs):
        for name, args in [("regions", levels), ("union", union)] + separate:
            r = run(binary, args, os.path.join(out, f"t1_{name}.vtu"), os.path.join(out, f"t1_{name}.json"))
            per_tet = r["timings_seconds"]["mesh"] / r["tets"]
            if name not in best or per_tet < best[name][0]:
                best[name] = (per_tet, r)
    return best


def cut(points, tets, regions, z):
    """The polygons where the plane z cuts the tets (3 or 4 corners each) and their regions."""
    zt = points[tets][:, :, 2]
    hit = (zt.min(axis=1) < z) & (zt.max(axis=1) > z)
    t, reg = tets[hit], regions[hit]
    p = points[t]
    edges = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    polys = [[] for _ in range(len(t))]
    for a, b in edges:
        za, zb = p[:, a, 2], p[:, b, 2]
        cross = (za - z) * (zb - z) < 0
        s = (z - za[cross]) / (zb[cross] - za[cross])
        q = p[cross, a, :2] + s[:, None] * (p[cross, b, :2] - p[cross, a, :2])
        for i, pt in zip(np.nonzero(cross)[0], q):
            polys[i].append(pt)
    out = []
    for poly in polys:
        poly = np.array(poly)
        c = poly.mean(axis=0)
        out.append(poly[np.argsort(np.arctan2(poly[:, 1] - c[1], poly[:, 0] - c[0]))])
    return out, reg


def picture(vtu, png):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import meshio
    from matplotlib.collections import PolyCollection

    m = meshio.read(vtu)
    tets = m.cells_dict["tetra"]
    regions = m.cell_data["region"][0]
    polys, reg = cut(m.points, tets, regions, CUT_Z)
    colors = np.array(["#4c72b0", "#c9b27c", "#e8e8e8"])[reg]
    fig, ax = plt.subplots(figsize=(5.2, 6.0), dpi=90)
    ax.add_collection(PolyCollection(polys, facecolors=colors, edgecolors="#333333", linewidths=0.05))
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set_axis_off()
    names = NAMES.split(",")
    for k, (n, c) in enumerate(zip(names, ["#4c72b0", "#c9b27c", "#e8e8e8"])):
        ax.plot([], [], "s", color=c, markeredgecolor="#333333", label=f"{n} [{LEVELS[k]}, {LEVELS[k + 1]}]")
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, -0.08), ncol=3, fontsize=8, frameon=False)
    ax.set_title(f"MNI152 T1, three regions in one mesh: axial cut at z = {CUT_Z} mm", fontsize=9)
    fig.savefig(png, bbox_inches="tight")


def machine():
    """The CPU model, cores and memory, as /proc says."""
    model = platform.machine()
    for line in open("/proc/cpuinfo"):
        if line.startswith("model name"):
            model = line.split(":", 1)[1].strip()
            break
    kb = int(next(l for l in open("/proc/meminfo") if l.startswith("MemTotal")).split()[1])
    return f"{model}, {os.cpu_count()} cores, {kb / 2**20:.0f} GiB"


def report(best, path):
    r, u = best["regions"][1], best["union"][1]
    ratio = best["regions"][0] / best["union"][0]
    parts = [best[f"region{k}"][1] for k in range(len(LEVELS) - 1)]
    sep_tets = sum(p["tets"] for p in parts)
    sep_time = sum(p["timings_seconds"]["mesh"] for p in parts)
    sep_ratio = best["regions"][0] / (sep_time / sep_tets)
    rows = "\n".join(
        f"| {g['name']} | [{g['levels'][0]}, {g['levels'][1]}] | {g['tets']:,} | {g['volume']:.0f} | "
        f"{tuple(g['betti'])} |"
        for g in r["regions"]
    )
    text = f"""# Several regions in one pass: cost per tet against the union

Machine: {machine()}, `-j 2`, release build.
Command: `python3 benchmarks/levels.py` (alternating runs, best of each; mesh stage =
meshing with the analysis, streamed to disk: `timings_seconds.mesh`).

Input: MNI152 2009a T1 (nilearn, uint8, 197 x 233 x 189), levels {', '.join(LEVELS)}.

| run | tets | mesh stage (s) | per tet (ns) |
|---|---:|---:|---:|
| `--levels {','.join(LEVELS)}` (3 regions) | {r['tets']:,} | {r['timings_seconds']['mesh']:.3f} | {1e9 * best['regions'][0]:.1f} |
| `--alpha {LEVELS[0]}` (their union) | {u['tets']:,} | {u['timings_seconds']['mesh']:.3f} | {1e9 * best['union'][0]:.1f} |
| the three regions in three runs (`--alpha`/`--beta`), summed | {sep_tets:,} | {sep_time:.3f} | {1e9 * sep_time / sep_tets:.1f} |

Per-tet cost ratio against the union: **{ratio:.3f}** (the goal: at most 1.3; not met). Against
the three regions meshed in three runs: **{sep_ratio:.3f}**.

Why: the union is mostly cells inside it, emitted as six whole tets without clipping; the
levels between the regions cut about twice as many tets out of the same cells, and a cut
cell costs more per tet (decomposition, clipping against each region whose interval its
values reach, welding the cut points). One pass costs {sep_ratio:.2f}× per tet what meshing
each region alone costs, and the mesh conforms.

| region | levels | tets | volume (mm³) | Betti numbers |
|---|---|---:|---:|---|
{rows}

The union's Betti numbers: {tuple(u['betti'])} (the regions' union mesh: {tuple(r['betti'])}).
"""
    open(path, "w").write(text)
    print(text)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default=os.path.join(HERE, "..", "target", "release", "tptd-mesh"))
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--no-picture", action="store_true")
    ap.add_argument("--picture-only", action="store_true", help="redraw from benchmarks/out/t1_regions.vtu")
    args = ap.parse_args()
    out = os.path.join(HERE, "out")
    os.makedirs(out, exist_ok=True)
    if args.picture_only:
        picture(os.path.join(out, "t1_regions.vtu"), os.path.join(HERE, "levels_slice.png"))
        return
    best = timing(args.bin, args.runs, out)
    report(best, os.path.join(HERE, "levels_results.md"))
    if not args.no_picture:
        picture(os.path.join(out, "t1_regions.vtu"), os.path.join(HERE, "levels_slice.png"))


if __name__ == "__main__":
    main()
