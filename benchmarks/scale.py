#!/usr/bin/env python3
"""Memory and scale: peak RSS, time and tets/s of streamed meshing on big volumes.

Volumes (generated into benchmarks/data/, git-ignored; never commit them):

  noisy_256.npy, noisy_512.npy   float32 noisy distance fields (benchmarks/make_data.py
                                 --sizes 256 512), meshed at their 80th percentile
                                 (f >= p80: a fifth of the volume inside)
  ball_1024_u8.npy               uint8 1024^3, a ball of radius 100 voxels (255 inside,
                                 logistic edge of width 2 voxels), meshed at f >= 127.3

Each run is `tptd-mesh VOL -o OUT --alpha A -j 2 --no-critical-check --report R.json` under
`/usr/bin/time -f %M` (peak RSS); outputs go to a temporary folder and are deleted.

Usage:
  python3 benchmarks/make_data.py --sizes 256 512   # once (about 2 minutes)
  python3 benchmarks/scale.py [--bin target/release/tptd-mesh] [--skip-1024]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "data")


def ball_1024():
    path = os.path.join(DATA, "ball_1024_u8.npy")
    if os.path.exists(path):
        return path
    n, r = 1024, 100.0
    a = np.lib.format.open_memmap(path, mode="w+", dtype=np.uint8, shape=(n, n, n))
    z = np.arange(n, dtype=np.float32) - (n - 1) / 2
    for k in range(n):
        d = np.sqrt(z[:, None] ** 2 + z[None, :] ** 2 + z[k] ** 2)
        t = np.clip((d - r) / 2.0, -50, 50)
        a[k] = np.clip(np.rint(255 / (1 + np.exp(t))), 0, 255).astype(np.uint8)
    a.flush()
    del a
    return path


def p80(path):
    a = np.load(path, mmap_mode="r")
    step = max(1, a.shape[0] // 128)
    return round(float(np.percentile(np.asarray(a[::step, ::step, ::step]), 80)), 2)


def run(binary, vol, alpha, out, extra=()):
    with tempfile.TemporaryDirectory(dir=HERE) as tmp:
        report = os.path.join(tmp, "r.json")
        cmd = ["/usr/bin/time", "-f", "%M", binary, vol, "-o", os.path.join(tmp, out),
               "--alpha", str(alpha), "-j", "2", "-q", "--no-critical-check",
               "--report", report, *extra]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"failed: {' '.join(cmd)}\n{p.stderr}")
        rss_kb = int(p.stderr.strip().splitlines()[-1])
        r = json.load(open(report))
        size = os.path.getsize(os.path.join(tmp, out))
    t = r["timings_seconds"]
    return {
        "tets": r["tets"], "total": t["total"], "mesh": t["mesh"], "write": t["write"],
        "rss": rss_kb * 1024, "out": size, "input": os.path.getsize(vol),
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default=os.path.join(HERE, "..", "target", "release", "tptd-mesh"))
    ap.add_argument("--skip-1024", action="store_true")
    args = ap.parse_args()
    rows = []
    for n in (256, 512):
        vol = os.path.join(DATA, f"noisy_{n}.npy")
        if not os.path.exists(vol):
            sys.exit(f"{vol} missing: python3 benchmarks/make_data.py --sizes 256 512")
        a = p80(vol)
        rows.append((f"noisy {n}³ float32", f"[{a}, inf)", ".vtu", run(args.bin, vol, a, "m.vtu")))
        if n == 512:
            rows.append((f"noisy {n}³ float32", f"[{a}, inf)", ".msh binary",
                         run(args.bin, vol, a, "m.msh", ["--msh-version", "4.1-binary"])))
    if not args.skip_1024:
        rows.append(("ball 1024³ uint8", "[127.3, inf)", ".vtu",
                     run(args.bin, ball_1024(), 127.3, "m.vtu")))
    print(f"load average {os.getloadavg()[0]:.1f}; {os.cpu_count()} cores")
    print("| volume | interval | output | tets | s | tets/s | peak RSS GB | input GB | output GB |")
    print("|---|---|---|--:|--:|--:|--:|--:|--:|")
    for name, interval, fmt, m in rows:
        print(f"| {name} | {interval} | {fmt} | {m['tets'] / 1e6:.1f} M | {m['total']:.1f} | "
              f"{m['tets'] / m['total'] / 1e6:.2f} M | {m['rss'] / 1e9:.2f} | "
              f"{m['input'] / 1e9:.2f} | {m['out'] / 1e9:.2f} |")


if __name__ == "__main__":
    main()
