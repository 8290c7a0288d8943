#!/usr/bin/env python3
"""Thin intervals: does `tptd-mesh --quality` keep the mesh valid and its volume on domains
whose two level sets are a fraction of a voxel apart?

  python3 benchmarks/thin_intervals.py                      # all five domains
  python3 benchmarks/thin_intervals.py --domains shell,noise4
  python3 benchmarks/thin_intervals.py --bin path/to/tptd-mesh

Five domains, written to benchmarks/data/thin/ (git-ignored, never commit it):

  t1_054   64^3 crop t1[66:130, 84:148, 62:126] of the MNI152 2009a T1 that nilearn ships
           (located as make_data.py does, uint8), band [150.23, 150.77]: 0.54 grey levels
  t1_14    the same crop, band [149.83, 151.23]: 1.4 grey levels
  smooth   48^3 white noise (seed 20240611) blurred by a Gaussian of std 2.5 voxels
           (scipy.ndimage, periodic), scaled to mean 0 and std 1; band [0.2987, 0.3287],
           3 % of its std around 0.3137
  noise4   4^3 uniform white noise in [0, 1) (seed 20240611), band [0.4987, 0.5287]
  shell    48^3 sphere distance |x - c| - 16, c = (23.6, 23.3, 23.45), band [-0.075, 0.075]:
           a shell 0.15 voxel thick

The bounds avoid grid values and, on the integer T1, the half-integers where its face saddles
and many critical values lie. Each domain is meshed twice by the release binary, each run a
fresh process, both with `--check`:

  tptd-mesh IN.npy --alpha A --beta B --check --report R.json -o OUT.vtu [--quality]

and the table gives both volumes (the report's `volume`; a failed check writes no mesh and no
report, so such a run is repeated without `--check` for the volume and the summary), the change, the trilinear volume of the interval
(`trilinear_volume.band_volume`, quadrature on 32 x 32 lines per cut cell; its change from
16 x 16 shows the quadrature error), whether `--check` passed and, if not, its one-line reason
and the largest level-set distance it found, the quality summary (tets below 15 and 5 degrees,
the reasons of those below 5, level nodes left off their level set) and the wall time.

Volume rule: `--quality` keeps the volume within 0.5 % of the plain mesh, or closer to the
trilinear volume than the plain mesh is.

Writes benchmarks/thin_intervals_results.{md,json}; meshes and reports go to
benchmarks/out/thin_intervals/ (git-ignored).
"""
import argparse
import datetime
import json
import math
import os
import platform
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
DATA = os.path.join(HERE, "data", "thin")
OUT = os.path.join(HERE, "out", "thin_intervals")
sys.path.insert(0, HERE)

import make_data  # noqa: E402  (locates the nilearn MNI volumes)
from trilinear_volume import band_volume  # noqa: E402

SEED = 20240611
T1_CROP = (slice(66, 130), slice(84, 148), slice(62, 126))
VOLUME_RULE = 0.005  # relative


# ----------------------------------------------------------------------------
# the volumes
# ----------------------------------------------------------------------------

def t1_crop():
    d = make_data.nilearn_data_dir()
    if d is None:
        sys.exit("thin_intervals: nilearn is not importable (pip install nilearn)")
    import nibabel as nib

    a = np.asarray(nib.load(os.path.join(d, make_data.T1_NAME)).dataobj)
    return np.ascontiguousarray(a[T1_CROP])


def smooth_field():
    from scipy.ndimage import gaussian_filter

    rng = np.random.default_rng(SEED)
    f = gaussian_filter(rng.standard_normal((48, 48, 48)), 2.5, mode="wrap")
    f = (f - f.mean()) / f.std()
    return f.astype("<f8")


def white_noise4():
    return np.random.default_rng(SEED).random((4, 4, 4)).astype("<f8")


def shell():
    i = np.arange(48, dtype=np.float64)
    c = (23.6, 23.3, 23.45)
    r = np.sqrt((i[:, None, None] - c[0]) ** 2 + (i[None, :, None] - c[1]) ** 2
                + (i[None, None, :] - c[2]) ** 2)
    return (r - 16.0).astype("<f8")


# key: (what the table says, file name, generator, alpha, beta)
DOMAINS = {
    "t1_054": ("T1 crop 64³, band 0.54 grey levels", "t1_crop64.npy", t1_crop, 150.23, 150.77),
    "t1_14": ("T1 crop 64³, band 1.4 grey levels", "t1_crop64.npy", t1_crop, 149.83, 151.23),
    "smooth": ("smooth random field 48³, band 3 % of its std", "smooth48.npy", smooth_field,
               0.2987, 0.3287),
    "noise4": ("seeded 4³ white noise, band 0.03 of its range [0, 1)", "noise4.npy", white_noise4,
               0.4987, 0.5287),
    "shell": ("spherical shell 0.15 voxel thick, radius 16, 48³", "shell48.npy", shell,
              -0.075, 0.075),
}


def volume_file(key, force):
    _, name, make, _, _ = DOMAINS[key]
    path = os.path.join(DATA, name)
    if force or not os.path.exists(path):
        os.makedirs(DATA, exist_ok=True)
        np.save(path, make())
    return path


# ----------------------------------------------------------------------------
# the runs
# ----------------------------------------------------------------------------

def run(binary, path, alpha, beta, tag, quality):
    out = os.path.join(OUT, tag + ".vtu")
    rep = os.path.join(OUT, tag + ".json")
    for p in (out, rep):
        if os.path.exists(p):
            os.remove(p)
    cmd = [binary, path, "--alpha", repr(alpha), "--beta", repr(beta), "--check",
           "--report", rep, "-o", out]
    if quality:
        cmd.append("--quality")
    t0 = time.perf_counter()
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    err = [ln.replace(REPO + os.sep, "") for ln in p.stderr.splitlines() if "error" in ln]
    failed = p.returncode != 0 and any("fails --check" in ln for ln in err)
    rerun = None
    if failed:
        # A failed check writes neither the mesh nor the report: run again without --check
        # for the volume and the quality summary.
        t1 = time.perf_counter()
        subprocess.run([c for c in cmd if c != "--check"], stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        rerun = time.perf_counter() - t1
    r = {}
    if os.path.exists(rep):
        with open(rep) as f:
            r = json.load(f)
    if os.path.exists(out):
        os.remove(out)
    chk = r.get("check") or {}
    volume = r.get("volume")
    if volume is None:
        volume = chk.get("volume")
    row = {
        "command": " ".join(os.path.relpath(c, REPO) if os.path.isabs(c) else c for c in cmd),
        "exit": p.returncode,
        "seconds": wall,
        "seconds_without_check": rerun,
        "tets": r.get("tets", chk.get("tets")),
        "volume": volume,
        "check_valid": chk.get("valid", False if failed else None),
        "check_line": err[-1] if (p.returncode != 0 and err) else None,
        "check_problems": {q["kind"]: q["count"] for q in chk.get("problems", [])},
        "check_level": chk.get("level"),
        "check_winding": chk.get("winding"),
        "betti": chk.get("betti"),
        "warnings": [w.replace(REPO + os.sep, "") for w in r.get("warnings", [])],
    }
    q = r.get("quality")
    if quality and q:
        forced = (q.get("forced") or {}).get("counts") or {}
        row["quality"] = {
            "min_before": q["before"]["min_dihedral"], "max_before": q["before"]["max_dihedral"],
            "min_after": q["after"]["min_dihedral"], "max_after": q["after"]["max_dihedral"],
            "tets_before": q["before"]["tets"], "tets_after": q["after"]["tets"],
            "below15": q["after"]["below"][2], "below5": q["after"]["below"][0],
            "forced": forced,
            "off_level": q["pass"].get("unprojected"),
            "pass_seconds": q["pass"].get("seconds"),
        }
    return row


def measure(binary, key, force, m):
    name, _, _, alpha, beta = DOMAINS[key]
    path = volume_file(key, force)
    d = np.load(path)
    t0 = time.perf_counter()
    tri = band_volume(d, alpha, beta, m)
    tri_half = band_volume(d, alpha, beta, m // 2)
    tri_s = time.perf_counter() - t0
    plain = run(binary, path, alpha, beta, key + "_plain", False)
    qual = run(binary, path, alpha, beta, key + "_quality", True)
    row = {"key": key, "domain": name, "file": os.path.relpath(path, REPO),
           "shape": list(d.shape), "dtype": str(d.dtype), "alpha": alpha, "beta": beta,
           "trilinear": tri, "trilinear_change_from_half": tri - tri_half,
           "trilinear_seconds": tri_s, "plain": plain, "quality": qual}
    vp, vq = plain["volume"], qual["volume"]
    if vp is not None and vq is not None:
        row["change"] = (vq - vp) / vp
        row["volume_rule"] = bool(abs(vq - vp) <= VOLUME_RULE * abs(vp)
                                  or abs(vq - tri) <= abs(vp - tri))
    return row


# ----------------------------------------------------------------------------
# the table
# ----------------------------------------------------------------------------

def check_cell(r):
    if r["check_valid"]:
        return "valid"
    if r["check_valid"] is None:
        return f"exit {r['exit']}, no check"
    if not r["check_problems"] and r["check_line"]:
        line = r["check_line"].split("fails --check (", 1)[-1].rsplit(")", 1)[0]
        return f"**{line}**"
    lv = r["check_level"] or {}
    probs = ", ".join(f"{v} {k}" for k, v in r["check_problems"].items())
    extra = ""
    if "off_level" in r["check_problems"] and lv:
        extra = f" (farthest {lv['max_beyond']:.3f} voxel, {lv['beyond']} of {lv['points']} points)"
    return f"**{probs}**{extra}"


def quality_cell(r):
    q = r.get("quality")
    if not q:
        return "–"
    reasons = ", ".join(f"{v} {k}" for k, v in q["forced"].items() if v)
    return (f"{q['min_after']:.2f}°–{q['max_after']:.1f}°, {q['below15']} below 15°, "
            f"{q['below5']} below 5°{' (' + reasons + ')' if reasons else ''}; "
            f"{q['off_level']} left off")


def fmt_vol(v):
    if v is None:
        return "–"
    return f"{v:,.4g}".replace(",", " ") if abs(v) < 100 else f"{v:,.1f}".replace(",", " ")


def table(rows):
    lines = [
        "| domain | interval | trilinear volume | plain: volume, `--check`, s "
        "| `--quality`: volume, change, `--check`, s | volume rule | `--quality` below 15° / 5° "
        "(reasons below 5°), left off |",
        "|---|---|--:|---|---|---|---|",
    ]
    for r in rows:
        p, q = r["plain"], r["quality"]
        ch = f"{100 * r['change']:+.2f} %" if "change" in r else "–"
        rule = {True: "kept", False: "**not kept**"}.get(r.get("volume_rule"), "–")
        lines.append(
            f"| {r['domain']} | [{r['alpha']}, {r['beta']}] | {fmt_vol(r['trilinear'])} "
            f"| {fmt_vol(p['volume'])}, {check_cell(p)}, {p['seconds']:.1f} s "
            f"| {fmt_vol(q['volume'])}, {ch}, {check_cell(q)}, {q['seconds']:.1f} s "
            f"| {rule} | {quality_cell(q)} |")
    return "\n".join(lines)


def machine():
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name"))
        with open("/proc/meminfo") as f:
            mem = int(next(ln.split()[1] for ln in f if ln.startswith("MemTotal"))) / 2 ** 20
        cpu += f", {mem:.0f} GiB"
    except (OSError, StopIteration, ValueError):
        pass
    return f"{os.cpu_count()}-core {cpu}"


def write_md(res):
    head = (
        f"# Thin intervals: plain ctd and `--quality`\n\n`{res['command']}`, {res['date']}, "
        f"{res['machine']}, load average after the run {' '.join(res['load'])} (the machine "
        "shared with other jobs). Each run: `tptd-mesh IN.npy --alpha A --beta B --check "
        "--report R.json -o OUT.vtu [--quality]`, release build, a fresh process; s is its wall "
        "time with `--check`. Volumes in voxels; the trilinear volume is the interval's under "
        f"trilinear interpolation (quadrature, {res['quadrature']}² lines per cut cell). Volume "
        "rule: `--quality` within 0.5 % of the plain mesh, or closer to the trilinear volume. "
        "A failed `--check` is its one-line reason (the run was repeated without `--check` for "
        "the volume and the quality summary). Domains and bands: the script's docstring.\n\n")
    with open(os.path.join(HERE, "thin_intervals_results.md"), "w") as f:
        f.write(head + table(res["rows"]) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", default=os.environ.get("TPTD_BIN",
                    os.path.join(REPO, "target", "release", "tptd-mesh")))
    ap.add_argument("--domains", default=",".join(DOMAINS),
                    help="comma-separated, of " + ", ".join(DOMAINS))
    ap.add_argument("--quadrature", type=int, default=32,
                    help="lines per cut cell along x and y for the trilinear volume (default 32)")
    ap.add_argument("--force", action="store_true", help="regenerate the volumes")
    ap.add_argument("--rewrite", action="store_true",
                    help="only rewrite the .md from thin_intervals_results.json")
    args = ap.parse_args()
    js = os.path.join(HERE, "thin_intervals_results.json")
    if args.rewrite:
        with open(js) as f:
            write_md(json.load(f))
        return
    if not os.path.exists(args.bin):
        sys.exit(f"thin_intervals: {args.bin} is missing (cargo build --release)")
    os.makedirs(DATA, exist_ok=True)
    os.makedirs(OUT, exist_ok=True)
    keys = [k for k in args.domains.split(",") if k]
    for k in keys:
        if k not in DOMAINS:
            sys.exit(f"thin_intervals: unknown domain {k} (of {', '.join(DOMAINS)})")
    rows = []
    for k in keys:
        rows.append(measure(args.bin, k, args.force, args.quadrature))
        print(table(rows[-1:]).splitlines()[-1], flush=True)
    with open("/proc/loadavg") as f:
        load = f.read().split()[:3]
    res = {"date": str(datetime.date.today()),
           "command": " ".join(["python3 benchmarks/thin_intervals.py"] + sys.argv[1:]),
           "machine": machine(), "load": load, "quadrature": args.quadrature, "rows": rows}
    with open(js, "w") as f:
        json.dump(res, f, indent=1)
    write_md(res)
    print(table(rows))


if __name__ == "__main__":
    main()
