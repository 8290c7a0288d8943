"""Paired timing of the quality pass of two builds of `tptd-mesh` on the full-size volumes.

  python3 benchmarks/quality_pair.py OLD_BINARY NEW_BINARY [--reps 3] [--volumes wm,t1,noisy]

Runs `--quality -j 2 --vtu-encoding raw` on each volume of `quality_full.py` (and on the T1's
two darker bands, `t1_51` = [51.5, 101.5] and `t1_101` = [101.5, 151.5]), alternating the
two binaries `--reps` times, so that both see the same machine load; prints the median pass
and the median of each stage (`quality.pass.stage_seconds`) per build, with the median
meshing time, pass ÷ meshing, and the mesh's tets and volume (of the last run). Build the old binary
from a worktree, e.g. `git worktree add /tmp/old <commit> && cd /tmp/old &&
CARGO_TARGET_DIR=/tmp/old-target cargo build --release`.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from quality_full import T1_FILE, VOLUMES, nilearn_file  # noqa: E402

BANDS = {
    "t1_51": ("MNI152 T1", lambda: nilearn_file(T1_FILE), ["--alpha", "51.5", "--beta", "101.5"],
              "[51.5, 101.5]"),
    "t1_101": ("MNI152 T1", lambda: nilearn_file(T1_FILE),
               ["--alpha", "101.5", "--beta", "151.5"], "[101.5, 151.5]"),
}


def run(binary, path, interval, out_dir):
    out, rep = os.path.join(out_dir, "m.vtu"), os.path.join(out_dir, "r.json")
    cmd = [binary, path, *interval, "-j", "2", "--no-critical-check", "-o", out,
           "--vtu-encoding", "raw", "--report", rep, "-q", "--quality"]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    with open(rep) as f:
        r = json.load(f)
    os.remove(out)
    p = r["quality"]["pass"]
    return {"mesh": r["timings_seconds"]["mesh"], "pass": p["seconds"],
            "ratio": p["seconds"] / r["timings_seconds"]["mesh"], **p["stage_seconds"],
            "tets": r["tets"], "volume": r["volume"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--volumes", default="wm,t1,noisy")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for key in a.volumes.split(","):
            name, path, interval, shown = {**VOLUMES, **BANDS}[key]
            runs = {"old": [], "new": []}
            for _ in range(a.reps):
                for which in ("old", "new"):
                    runs[which].append(run(getattr(a, which), path(), interval, tmp))
            for which, rs in runs.items():
                med = {k: round(statistics.median(r[k] for r in rs), 2) for k in rs[0]
                       if k not in ("tets", "volume")}
                med["tets"], med["volume"] = rs[-1]["tets"], round(rs[-1]["volume"], 3)
                print(f"{name} {shown} {which}: " + ", ".join(f"{k} {v}" for k, v in med.items()))
    print("load average:", " ".join(f"{x:.2f}" for x in os.getloadavg()))


if __name__ == "__main__":
    main()
