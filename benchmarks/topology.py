#!/usr/bin/env python3
"""Betti numbers of the benchmark intervals for ctd, tptd and six: the README's topology table.

  python3 benchmarks/make_data.py --sizes 128,256   # volumes and intervals (manifest.json)
  python3 benchmarks/topology.py                     # writes benchmarks/topology_results.md
  python3 benchmarks/topology.py --bin path/to/tptd-mesh

Each interval of benchmarks/data/manifest.json is meshed by each method (vtu to a temporary
folder, deleted); the Betti numbers (components, tunnels, cavities) come from `--report`.
"""
import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
METHODS = ["ctd", "tptd", "six", "five"]


def fmt(v, sign):
    return sign + "inf" if v is None else repr(v)


def interval_args(lo, hi):
    args = []
    if lo is not None:
        args.append(f"--alpha={lo!r}")
    if hi is not None:
        args.append(f"--beta={hi!r}")
    return args


def betti(binary, path, lo, hi, method, tmp):
    out, rep = os.path.join(tmp, "m.vtu"), os.path.join(tmp, "r.json")
    cmd = [binary, path, *interval_args(lo, hi), "--method", method, "-o", out, "--report", rep,
           "-q"]
    run = subprocess.run(cmd, capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"failed: {' '.join(cmd)}\n{run.stderr}")
    with open(rep) as f:
        report = json.load(f)
    os.remove(out)
    return report["betti"], report["tets"], [w for w in report["warnings"]]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=os.path.join(REPO, "target", "release", "tptd-mesh"))
    ap.add_argument("--out", default=os.path.join(HERE, "topology_results.md"))
    args = ap.parse_args()
    with open(os.path.join(HERE, "data", "manifest.json")) as f:
        datasets = json.load(f)["datasets"]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, ds in datasets.items():
            if not os.path.exists(ds["path"]):
                print(f"missing {name}: {ds['path']}", file=sys.stderr)
                continue
            for lo, hi in ds["intervals"]:
                cells, warnings = [], 0
                for m in METHODS:
                    b, tets, w = betti(args.bin, ds["path"], lo, hi, m, tmp)
                    warnings += len(w)
                    cells.append(f"{b[0]}, {b[1]}, {b[2]}")
                    print(f"{name} [{fmt(lo, '-')}, {fmt(hi, '')}] {m}: betti {b}, {tets} tets", flush=True)
                rows.append(f"| {name} ({ds['dtype']}) | [{fmt(lo, '-')}, {fmt(hi, '')}] | "
                            + " | ".join(cells) + f" | {warnings} |")
    cpu = "unknown"
    if os.path.exists("/proc/cpuinfo"):
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    lines = [
        "# Topology of the benchmark intervals",
        "",
        f"Generated {datetime.datetime.now().isoformat(timespec='seconds')} on {platform.node()} "
        f"({cpu}, {os.cpu_count()} CPUs) by",
        "",
        "```",
        "python3 benchmarks/make_data.py --sizes 128,256",
        "python3 benchmarks/topology.py",
        "```",
        "",
        "Betti numbers b0, b1, b2 (components, tunnels, cavities) of each mesh, from `--report`. "
        "`ctd` and `tptd` have the topology of the trilinear interpolant (the test suite checks "
        "them against an independent reference); `six` and `five` split each voxel into 6 or 5 "
        "tetrahedra and do not. The bounds on the `uint8` MNI volumes are neither integers nor "
        "k + 0.5 (`make_data.py`, `safe_level`); `warnings` counts the bound warnings of all runs "
        "of the row (0: no bound near a critical value).",
        "",
        "| volume | interval | " + " | ".join(f"`{m}`" for m in METHODS) + " | warnings |",
        "|---|---|" + "---|" * len(METHODS) + "--:|",
        *rows,
        "",
    ]
    with open(args.out, "w") as f:
        f.write("\n".join(lines))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
