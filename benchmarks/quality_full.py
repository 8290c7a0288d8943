#!/usr/bin/env python3
"""Full-size quality-pass timing: `tptd-mesh --quality` against plain meshing on the MNI152
white matter and T1 volumes (from the installed nilearn package) and the 256^3 noisy field
of make_data.py, one series of runs on this machine.

  python3 benchmarks/quality_full.py                 # 1 repetition, all three volumes
  python3 benchmarks/quality_full.py --reps 3        # median of 3
  python3 benchmarks/quality_full.py --volumes wm,t1

For each volume, in turn: the plain run (`-j 2 --no-critical-check`, streamed), then the
same with `--quality`, each a fresh process writing a raw `.vtu` and a `--report`. The table
gives the report's `mesh` stage of both (the `--quality` run meshes with warping), the pass
(`quality.pass.seconds`), both ratios the issue can mean (pass / meshing of the same run, and
warping plus pass / plain meshing), the dihedral range after, tets below 15 and 5 degrees,
the reasons of those below 5, and the level vertices left off their level set.

Writes benchmarks/quality_full_results.{md,json}; outputs go to benchmarks/out/quality_full/
(git-ignored).
"""
import argparse
import datetime
import json
import os
import platform
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
OUT = os.path.join(HERE, "out", "quality_full")


def nilearn_file(name):
    import nilearn  # noqa: imported only for its data directory

    return os.path.join(os.path.dirname(nilearn.__file__), "datasets", "data", name)


# The MNI152 2009a volumes that nilearn ships.
WM_FILE = "mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz"
T1_FILE = "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz"

VOLUMES = {
    "wm": ("MNI152 white matter", lambda: nilearn_file(WM_FILE), ["--alpha", "127.5"],
           "[127.5, inf)"),
    "t1": ("MNI152 T1", lambda: nilearn_file(T1_FILE),
           ["--alpha", "151.5", "--beta", "201.5"], "[151.5, 201.5]"),
    "noisy": ("noisy distance field 256³", lambda: os.path.join(HERE, "data", "noisy_256.npy"),
              ["--alpha", "-2", "--beta", "2"], "[-2, 2]"),
}


def run(binary, path, interval, tag, quality):
    out = os.path.join(OUT, tag + ".vtu")
    rep = os.path.join(OUT, tag + ".json")
    cmd = [binary, path, *interval, "-j", "2", "--no-critical-check", "-o", out,
           "--vtu-encoding", "raw", "--report", rep, "-q"]
    if quality:
        cmd.append("--quality")
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    with open(rep) as f:
        r = json.load(f)
    os.remove(out)
    return r


def measure(binary, key, reps):
    name, path, interval, shown = VOLUMES[key]
    path = path()
    if not os.path.exists(path):
        sys.exit(f"quality_full: {path} is missing (python3 benchmarks/make_data.py --sizes 256)")
    plain, qual = [], []
    for i in range(reps):
        plain.append(run(binary, path, interval, f"{key}_plain_{i}", False))
        qual.append(run(binary, path, interval, f"{key}_quality_{i}", True))
    med = statistics.median
    q = qual[-1]["quality"]
    row = {
        "volume": name, "interval": shown,
        "plain_mesh_s": med(r["timings_seconds"]["mesh"] for r in plain),
        "warp_mesh_s": med(r["timings_seconds"]["mesh"] for r in qual),
        "pass_s": med(r["quality"]["pass"]["seconds"] for r in qual),
        "tets_before": q["before"]["tets"], "tets_after": q["after"]["tets"],
        "min_after": q["after"]["min_dihedral"], "max_after": q["after"]["max_dihedral"],
        "below15": q["after"]["below"][2], "below5": q["after"]["below"][0],
        "forced": q["forced"]["counts"] if q.get("forced") else None,
        "off_level": q["pass"]["unprojected"],
        "stage_seconds": q["pass"]["stage_seconds"],
    }
    row["pass_over_mesh"] = row["pass_s"] / row["warp_mesh_s"]
    row["warp_and_pass_over_plain"] = (row["warp_mesh_s"] - row["plain_mesh_s"] + row["pass_s"]) \
        / row["plain_mesh_s"]
    return row


def table(rows):
    lines = [
        "| volume | interval | plain meshing | meshing with warping | quality pass | pass / meshing "
        "(same run) | (warping + pass) / plain | dihedral after | below 15° | below 5° (reasons) "
        "| left off the level set |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        f = r["forced"] or {}
        reasons = ", ".join(f"{v} {k}" for k, v in f.items() if v)
        lines.append(
            f"| {r['volume']} | {r['interval']} | {r['plain_mesh_s']:.2f} s | {r['warp_mesh_s']:.2f} s "
            f"| {r['pass_s']:.2f} s | {r['pass_over_mesh']:.1f}× | {r['warp_and_pass_over_plain']:.1f}× "
            f"| {r['min_after']:.2f}°–{r['max_after']:.1f}° | {r['below15']} of {r['tets_after']} "
            f"| {r['below5']}{' (' + reasons + ')' if reasons else ''} | {r['off_level']} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", default=os.environ.get("TPTD_BIN",
                    os.path.join(REPO, "target", "release", "tptd-mesh")))
    ap.add_argument("--reps", type=int, default=1)
    ap.add_argument("--volumes", default="wm,t1,noisy")
    args = ap.parse_args()
    os.makedirs(OUT, exist_ok=True)
    rows = []
    for key in args.volumes.split(","):
        rows.append(measure(args.bin, key, args.reps))
        print(table(rows[-1:]).splitlines()[-1], flush=True)
    with open("/proc/loadavg") as f:
        load = f.read().split()[:3]
    cpu = platform.processor() or platform.machine()
    head = (f"# Full-size quality pass\n\n`python3 benchmarks/quality_full.py --reps {args.reps}`, "
            f"{datetime.date.today()}, {os.cpu_count()} CPUs ({cpu}), load average after the "
            f"run {' '.join(load)}. Times are the report's stages (median of {args.reps}).\n\n")
    with open(os.path.join(HERE, "quality_full_results.md"), "w") as f:
        f.write(head + table(rows) + "\n")
    with open(os.path.join(HERE, "quality_full_results.json"), "w") as f:
        json.dump({"date": str(datetime.date.today()), "load": load, "rows": rows}, f, indent=1)
    print(table(rows))


if __name__ == "__main__":
    main()
