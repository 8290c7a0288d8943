#!/usr/bin/env python3
"""The Python package's overhead over tptd-mesh on the MNI152 white matter.

Alternates, in one run, `tptd.mesh(array, 127.0135)` (the array from `tptd.read_volume`, a
`meshio.Mesh` in memory: meshing, analysis and the conversion to numpy) with
`tptd-mesh WM --alpha 127.0135 -o wm.vtu` (its mesh stage: the report's total less reading
and writing). Prints each pair, the median ratio and the peak resident memory of each
(`VmHWM` above the baseline after reading for Python, GNU time's `%M` for the CLI),
and writes benchmarks/python_results.md.

Usage: python3 benchmarks/python_overhead.py [--runs 8] [--cli target/release/tptd-mesh]
(the `tptd` package installed: pip install ./python)
"""
import argparse
import json
import os
import platform
import statistics
import subprocess
import tempfile
import time

import nilearn
import tptd

HERE = os.path.dirname(os.path.abspath(__file__))
WM = os.path.join(os.path.dirname(nilearn.__file__), "datasets", "data",
                  "mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz")
ALPHA = 127.0135


def status(key):
    for line in open("/proc/self/status"):
        if line.startswith(key + ":"):
            return int(line.split()[1]) * 1024
    return 0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=8)
    ap.add_argument("--cli", default=os.path.join(HERE, "..", "target", "release", "tptd-mesh"))
    args = ap.parse_args()
    a, _ = tptd.read_volume(WM)
    rows = []
    py_peak = cli_peak = 0
    with tempfile.TemporaryDirectory() as d:
        out, rep = os.path.join(d, "wm.vtu"), os.path.join(d, "r.json")
        for _ in range(args.runs):
            try:
                open("/proc/self/clear_refs", "w").write("5")
            except OSError:
                pass
            base = status("VmRSS")
            t = time.perf_counter()
            m = tptd.mesh(a, ALPHA)
            py = time.perf_counter() - t
            py_peak = max(py_peak, status("VmHWM") - base)
            tets = len(m.cells_dict["tetra"])
            del m
            cmd = [args.cli, WM, "--alpha", str(ALPHA), "-o", out, "--report", rep, "-q"]
            if os.path.exists("/usr/bin/time"):  # GNU time: the child's own peak, in KiB
                r = subprocess.run(["/usr/bin/time", "-f", "%M"] + cmd, check=True,
                                   capture_output=True, text=True)
                cli_peak = max(cli_peak, int(r.stderr.split()[-1]) * 1024)
            else:
                subprocess.run(cmd, check=True)
            c = json.load(open(rep))["timings_seconds"]
            cli = c["total"] - c["read"] - c["write"]
            rows.append((py, cli, py / cli))
            print(f"python {py:.3f} s, tptd-mesh mesh stage {cli:.3f} s, ratio {py / cli:.3f}")
    ratios = [r for _, _, r in rows]
    med = statistics.median(ratios)
    print(f"median ratio {med:.3f} (min {min(ratios):.3f}, max {max(ratios):.3f}); "
          f"peak memory: python {py_peak / 2**20:.0f} MiB above its baseline, "
          f"tptd-mesh {cli_peak / 2**20:.0f} MiB")
    with open(os.path.join(HERE, "python_results.md"), "w") as f:
        f.write("# Python package overhead (MNI152 white matter)\n\n")
        f.write(f"`python3 benchmarks/python_overhead.py --runs {args.runs}` on "
                f"{platform.node() or 'this machine'} ({os.cpu_count()} cores); "
                f"{tets} tets at alpha = {ALPHA}. `tptd.mesh` from the array of "
                "`tptd.read_volume` to a `meshio.Mesh` in memory, against the mesh stage of "
                "`tptd-mesh -o wm.vtu` (total less reading and writing), alternated in one "
                "run.\n\n| run | Python (s) | tptd-mesh mesh stage (s) | ratio |\n"
                "|---|---|---|---|\n")
        for i, (p, c, r) in enumerate(rows, 1):
            f.write(f"| {i} | {p:.3f} | {c:.3f} | {r:.3f} |\n")
        f.write(f"\nMedian ratio **{med:.3f}** (min {min(ratios):.3f}, max {max(ratios):.3f}). "
                f"Peak resident memory: Python {py_peak / 2**20:.0f} MiB above its baseline "
                f"after reading (the mesh held in memory and handed to numpy), tptd-mesh "
                f"{cli_peak / 2**20:.0f} MiB in all (the mesh streamed to disk).\n")


if __name__ == "__main__":
    main()
