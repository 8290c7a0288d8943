#!/usr/bin/env python3
"""`tptd-mesh --quality` on the full MNI152 volumes at several isovalues, each checked
against its plain mesh and independently of the mesher.

  python3 benchmarks/quality_alphas.py                # all intervals (about 3 minutes)
  python3 benchmarks/quality_alphas.py --only wm      # the white matter's only

For each interval: the plain run and the `--quality` run (`-j 2 --no-critical-check`, each a
fresh process with a `--report`), then, from the `--quality` run's `.vtu` read by meshio:
  * tets not positively oriented (numpy signed volumes);
  * boundary nodes on a level (`f` equal to alpha or beta) whose trilinear value, computed
    here from the NIfTI file (nibabel's affine, scipy's `map_coordinates(order=1)`), is off
    the level by more than 1e-6 of the data range;
and from the reports: the Betti numbers of both meshes (equal when the pass kept the
topology), the volume change, the dihedral range and the tets below 5° with their reasons,
and the pass against the meshing of the same run.

Writes benchmarks/quality_alphas_results.{md,json}; meshes go to benchmarks/out/quality_alphas/
(git-ignored) and are deleted after each check.
"""
import argparse
import datetime
import json
import os
import platform
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
OUT = os.path.join(HERE, "out", "quality_alphas")
sys.path.insert(0, HERE)
from quality import signed_volumes  # noqa: E402
from quality_full import T1_FILE as T1, WM_FILE as WM, nilearn_file  # noqa: E402

# (key, file, alpha, beta); None is an open end.
INTERVALS = [
    ("wm", WM, 63.5, None),
    ("wm", WM, 127.5, None),
    ("wm", WM, 191.5, None),
    ("t1", T1, 51.5, 101.5),
    ("t1", T1, 101.5, 151.5),
    ("t1", T1, 151.5, 201.5),
    ("t1", T1, 201.5, None),
]
REL_TOL = 1e-6


def run(binary, path, alpha, beta, tag, quality):
    out = os.path.join(OUT, tag + ".vtu")
    rep = os.path.join(OUT, tag + ".json")
    cmd = [binary, path, "--alpha", repr(alpha), "-j", "2", "--no-critical-check", "-o", out,
           "--report", rep, "-q"]
    cmd += ["--beta", repr(beta)] if beta is not None else []
    cmd += ["--quality"] if quality else ["--vtu-encoding", "raw"]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(rep) as f:
        return out, json.load(f)


def inverted(points, tets):
    """Tets whose signed volume is not positive."""
    return int((signed_volumes(points, tets) <= 0).sum())


def off_level(path, points, f, levels):
    """Level nodes (f equal to a level) whose trilinear value is off it by more than REL_TOL
    of the data range, and the largest such offset relative to the range."""
    import nibabel
    from scipy.ndimage import map_coordinates
    img = nibabel.load(path)
    data = np.asarray(img.dataobj, dtype=np.float64)
    rng = float(data.max() - data.min())
    inv = np.linalg.inv(img.affine)
    worst, bad = 0.0, 0
    for level in (x for x in levels if x is not None):
        on = np.flatnonzero(f == level)
        if len(on) == 0:
            continue
        p = points[on]
        ijk = p @ inv[:3, :3].T + inv[:3, 3]
        vals = map_coordinates(data, ijk.T, order=1, mode="nearest")
        err = np.abs(vals - level) / rng
        worst = max(worst, float(err.max()))
        bad += int((err > REL_TOL).sum())
    return bad, worst


def check(binary, key, name, alpha, beta):
    path = nilearn_file(name)
    tag = f"{key}_{alpha:g}_{'inf' if beta is None else format(beta, 'g')}"
    plain_out, plain = run(binary, path, alpha, beta, tag + "_plain", False)
    os.remove(plain_out)
    out, qual = run(binary, path, alpha, beta, tag + "_quality", True)
    import meshio
    m = meshio.read(out)
    os.remove(out)
    points = np.asarray(m.points, dtype=np.float64)
    tets = m.cells_dict["tetra"]
    f = np.asarray(m.point_data["f"], dtype=np.float64)
    q = qual["quality"]
    bad_level, worst = off_level(path, points, f, (alpha, beta))
    return {
        "volume": key, "alpha": alpha, "beta": beta,
        "tets": len(tets), "inverted": inverted(points, tets),
        "off_level": bad_level, "worst_level_offset": worst,
        "betti_plain": plain["betti"], "betti_quality": qual["betti"],
        "volume_change_pct": 100.0 * (qual["volume"] / plain["volume"] - 1.0),
        "min_dihedral": q["after"]["min_dihedral"], "max_dihedral": q["after"]["max_dihedral"],
        "below5": q["after"]["below"][0], "below15": q["after"]["below"][2],
        "forced": q["forced"]["counts"] if q.get("forced") else None,
        "mesh_s": qual["timings_seconds"]["mesh"], "pass_s": q["pass"]["seconds"],
    }


def interval(r):
    return f"[{r['alpha']:g}, {'inf)' if r['beta'] is None else format(r['beta'], 'g') + ']'}"


def row(r):
    forced = ", ".join(f"{v} {k}" for k, v in (r["forced"] or {}).items() if v)
    same = "yes" if r["betti_plain"] == r["betti_quality"] else "**no**"
    return (f"| {r['volume']} | {interval(r)} | {r['tets']} | {r['inverted']} | {r['off_level']} "
            f"({r['worst_level_offset']:.1e}) | {r['betti_quality']} ({same}) "
            f"| {r['volume_change_pct']:+.3f} % | {r['min_dihedral']:.2f}°–{r['max_dihedral']:.1f}° "
            f"| {r['below15']} | {r['below5']}{' (' + forced + ')' if forced else ''} "
            f"| {r['pass_s']:.1f} s / {r['mesh_s']:.1f} s = {r['pass_s'] / r['mesh_s']:.1f}× |")


HEAD = ("| volume | interval | tets | not positive | level nodes off (worst, of range) "
        "| Betti (as plain) | volume vs plain | dihedral | below 15° | below 5° (reasons) "
        "| pass / meshing |\n|---|---|---|---|---|---|---|---|---|---|---|")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", default=os.path.join(REPO, "target", "release", "tptd-mesh"))
    ap.add_argument("--only", choices=["wm", "t1"], help="one volume's intervals only")
    args = ap.parse_args()
    os.makedirs(OUT, exist_ok=True)
    rows = []
    print(HEAD, flush=True)
    for key, name, alpha, beta in INTERVALS:
        if args.only and key != args.only:
            continue
        rows.append(check(args.bin, key, name, alpha, beta))
        print(row(rows[-1]), flush=True)
    with open("/proc/loadavg") as f:
        load = f.read().split()[:3]
    cpu = platform.processor() or platform.machine()
    text = (f"# `--quality` on the MNI152 volumes at several isovalues\n\n"
            f"`python3 benchmarks/quality_alphas.py`, {datetime.date.today()}, {os.cpu_count()} "
            f"CPUs ({cpu}), load average after the run {' '.join(load)}. Times indicative "
            f"(one run each).\n\n{HEAD}\n" + "\n".join(row(r) for r in rows) + "\n")
    if not args.only:
        with open(os.path.join(HERE, "quality_alphas_results.md"), "w") as f:
            f.write(text)
        with open(os.path.join(HERE, "quality_alphas_results.json"), "w") as f:
            json.dump({"date": str(datetime.date.today()), "load": load, "rows": rows}, f,
                      indent=1)
    print(text)
    failed = [r for r in rows if r["inverted"] or r["off_level"]
              or r["betti_plain"] != r["betti_quality"]]
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
