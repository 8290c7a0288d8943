#!/usr/bin/env python3
"""Benchmark of `tptd-mesh --critical` on the MNI152 T1 volume (nilearn) against meshing the same
volume with ctd, in the same run, plus the contour-spectrum plot of a crop of it.

    pip install numpy nibabel nilearn matplotlib
    cargo build --release
    python3 benchmarks/critical.py            # writes benchmarks/critical_results.md and
                                              # benchmarks/critical_spectrum.png

Every timing is one fresh process, end to end (read + work + write), median of --reps runs,
the runs of the two commands interleaved so both see the same machine load.
"""
import argparse
import csv
import os
import platform
import statistics
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def mni_t1():
    import nilearn

    d = os.path.join(os.path.dirname(nilearn.__file__), "datasets", "data")
    return os.path.join(d, "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz")


def machine():
    cpu = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    return f"{os.cpu_count()} cores, {cpu}, {mem:.0f} GiB, {platform.system()} {platform.release()}"


def timed(cmd):
    t = time.perf_counter()
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    dt = time.perf_counter() - t
    if r.returncode != 0:
        sys.exit(f"failed: {' '.join(cmd)}\n{r.stderr}")
    return dt, r.stdout


def spectrum_plot(binary, out_dir, png):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import nibabel as nib

    vol = np.asarray(nib.load(mni_t1()).dataobj)
    # a 48^3 crop through the left hemisphere (grey and white matter, ventricle edge)
    crop = vol[50:98, 100:148, 80:128].astype(np.float64)
    npy = os.path.join(out_dir, "t1_crop48.npy")
    np.save(npy, crop)
    csv_path = os.path.join(out_dir, "t1_crop48_spectrum.csv")
    dt, _ = timed([binary, npy, "--critical", "-q", "--spectrum", csv_path])
    steps, crit = [], []
    with open(csv_path) as f:
        for row in f:
            if row.startswith("lo,"):
                continue
            if row.startswith("# ") and "," in row and not row.startswith("# critical"):
                v, k = row[2:].strip().split(",")
                crit.append((float(v), k))
            elif not row.startswith("#"):
                lo, hi, b0, b1, b2 = row.strip().split(",")
                steps.append((float(lo), float(hi), int(b0), int(b1), int(b2)))
    fig, ax = plt.subplots(figsize=(8, 4.2), dpi=80)
    for idx, (name, col) in enumerate([("b0", "tab:blue"), ("b1", "tab:orange"), ("b2", "tab:green")]):
        xs, ys = [], []
        for s in steps:
            xs += [s[0], s[1]]
            ys += [s[2 + idx], s[2 + idx]]
        ax.plot(xs, ys, color=col, lw=1.2, label=f"{name} of {{f >= w}}")
    colours = {
        "minimum": "tab:blue", "region_minimum": "tab:blue",
        "maximum": "tab:red", "region_maximum": "tab:red",
        "saddle": "tab:green", "face_saddle": "tab:olive", "body_saddle": "tab:purple",
        "region_saddle": "tab:green",
    }
    top = max(max(s[2:]) for s in steps) if steps else 1
    for kind in sorted({k for _, k in crit}):
        vs = [v for v, k in crit if k == kind]
        ax.plot(vs, [-0.04 * top] * len(vs), "|", ms=6, color=colours.get(kind, "k"), label=f"{kind} ({len(vs)})")
    ax.set_xlabel("isovalue w")
    ax.set_ylabel("Betti number")
    ax.set_yscale("symlog")
    ax.set_title("Contour spectrum of a 48³ crop of the MNI152 T1 (ticks: critical values by kind)", fontsize=9)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(png, dpi=80)
    return dt, len(steps), len(crit), crop.shape


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--bin", default=os.environ.get("TPTD_BIN", os.path.join(ROOT, "target/release/tptd-mesh")))
    args = ap.parse_args()
    out_dir = os.path.join(HERE, "out")
    os.makedirs(out_dir, exist_ok=True)
    t1 = mni_t1()
    cmds = {
        "critical": [args.bin, t1, "--critical", "-q"],
        "critical --persistence": [args.bin, t1, "--critical", "--persistence", "-q"],
        "ctd mesh [151.0135, 201.816]": [
            args.bin, t1, "--alpha", "151.0135", "--beta", "201.816", "-o",
            os.path.join(out_dir, "t1_ctd.vtu"), "--no-analysis", "-q", "--no-critical-check",
        ],
        "ctd mesh + bound check": [
            args.bin, t1, "--alpha", "151.0135", "--beta", "201.816", "-o",
            os.path.join(out_dir, "t1_ctd.vtu"), "--no-analysis", "-q",
        ],
    }
    times = {k: [] for k in cmds}
    for _ in range(args.reps):
        for k, c in cmds.items():
            times[k].append(timed(c)[0])
    _, table = timed([args.bin, t1, "--critical"])
    count = table.splitlines()[0].split(": ")[1].split(" critical")[0]
    med = {k: statistics.median(v) for k, v in times.items()}
    png = os.path.join(HERE, "critical_spectrum.png")
    sdt, nsteps, ncrit, shape = spectrum_plot(args.bin, out_dir, png)
    rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    lines = [
        "# `--critical` benchmark",
        "",
        f"Generated {time.strftime('%Y-%m-%dT%H:%M:%S')} by `benchmarks/critical.py` (git `{rev}`), "
        f"{args.reps} interleaved repetition(s), median wall time, machine: {machine()}; "
        f"load average at the end: {os.getloadavg()[0]:.1f}.",
        "",
        f"MNI152 T1 (197×233×189, uint8): {count} critical points and regions.",
        "",
        "| command | median s | all runs s |",
        "|---|---|---|",
    ]
    for k in cmds:
        lines.append(f"| `{k}` | {med[k]:.2f} | {', '.join(f'{x:.2f}' for x in times[k])} |")
    ratio = med["critical"] / med["ctd mesh [151.0135, 201.816]"]
    lines += [
        "",
        f"`--critical` / ctd meshing = {ratio:.2f} ({'PASS' if ratio < 1 else 'FAIL'}: must be below 1).",
        "",
        f"Contour spectrum: crop {shape}, {nsteps} intervals between {ncrit} critical values of "
        f"{{f >= w}}, `--critical --spectrum` in {sdt:.2f} s; plot `benchmarks/critical_spectrum.png`.",
        "",
    ]
    with open(os.path.join(HERE, "critical_results.md"), "w") as f:
        f.write("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
