#!/usr/bin/env python3
"""End-to-end benchmark of tptd-mesh (methods six / tptd / ctd, -j 1 / -j 2)
against a VTK peer (vtkClipVolume, tets only), see benchmarks/README.md.

Every measurement is a fresh process: process start -> read volume -> mesh ->
binary .vtu written.  Wall time is measured around the child with
time.perf_counter(); peak RSS is "Maximum resident set size" from GNU
`/usr/bin/time -v` wrapped around the child (fallback: ru_maxrss from os.wait4()).
Median over --reps repetitions (the RSS and outputs of the median-time rep are
reported).

  python3 benchmarks/run.py                 # 128^3, 256^3, MNI T1, MNI WM; 3 reps
  python3 benchmarks/run.py --quick         # 64^3 + MNI WM, 1 rep (smoke test, < 2 min)
  python3 benchmarks/run.py --sizes 128 --reps 5

Writes benchmarks/results.md and benchmarks/results.json (override with --out); --quick writes
benchmarks/results_quick.{md,json} (git-ignored) so a smoke test never overwrites a full run.
"""
import argparse
import datetime
import json
import os
import platform
import re
import shlex
import statistics
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
DATA = os.path.join(HERE, "data")
OUT = os.path.join(HERE, "out")

METHODS = ["six", "tptd", "ctd"]

# targets (evaluated and printed as PASS/FAIL)
TARGET_CTD_OVER_VTK = 10.0      # ctd output tets/s >= 10x VTK output tets/s
TARGET_TPTD_OVER_SIX = 1.3      # tptd seconds per output tet <= 1.3x six
TARGET_RSS_OVER_IO = 3.0        # peak RSS <= 3x (8 B x voxels + .vtu bytes)
RSS_MIN_VOXELS = 128 ** 3       # ... evaluated on inputs this large; below, the fixed process
                                # baseline dominates (reported as an INFO line)


# ----------------------------------------------------------------------------
# process measurement
# ----------------------------------------------------------------------------

TIME_BIN = "/usr/bin/time"
HAVE_GNU_TIME = os.access(TIME_BIN, os.X_OK)


def run_measured(cmd, log_prefix, timeout=None, env=None):
    """Run cmd as a fresh child; return dict(wall, maxrss_kb, rc, stdout, stderr).

    Peak RSS comes from GNU `/usr/bin/time -v` ("Maximum resident set size").  Without it we
    fall back to ru_maxrss from os.wait4(), which on Linux is inflated to at least the
    harness's own RSS at fork time (the high-water mark survives fork + exec), so the
    harness keeps itself small (no numpy/vtk imports) and warns."""
    out_path, err_path = log_prefix + ".stdout", log_prefix + ".stderr"
    tv_path = log_prefix + ".time"
    full = [TIME_BIN, "-v", "-o", tv_path] + list(cmd) if HAVE_GNU_TIME else list(cmd)
    with open(out_path, "wb") as fo, open(err_path, "wb") as fe:
        t0 = time.perf_counter()
        p = subprocess.Popen(full, stdout=fo, stderr=fe, env=env)
        killer = threading.Timer(timeout, p.kill) if timeout else None
        if killer:
            killer.start()
        _, status, ru = os.wait4(p.pid, 0)   # blocking; rusage of this child only
        wall = time.perf_counter() - t0
        if killer:
            killer.cancel()
        p.returncode = os.waitstatus_to_exitcode(status)
    maxrss_kb, rss_src = ru.ru_maxrss, "wait4"
    user, sys_t = ru.ru_utime, ru.ru_stime
    if HAVE_GNU_TIME and os.path.exists(tv_path):
        with open(tv_path, errors="replace") as f:
            tv = f.read()
        m = re.search(r"Maximum resident set size \(kbytes\):\s*(\d+)", tv)
        if m:
            maxrss_kb, rss_src = int(m.group(1)), "/usr/bin/time -v"
        m = re.search(r"Exit status:\s*(-?\d+)", tv)
        if m and p.returncode == 0:
            p.returncode = int(m.group(1))
        if "Command terminated by signal" in tv and p.returncode == 0:
            p.returncode = -1
    with open(out_path, "r", errors="replace") as f:
        so = f.read()
    with open(err_path, "r", errors="replace") as f:
        se = f.read()
    return {"wall": wall, "maxrss_kb": maxrss_kb, "rss_source": rss_src, "rc": p.returncode,
            "user": user, "sys": sys_t, "stdout": so, "stderr": se,
            "timed_out": bool(timeout) and wall >= timeout}


def vtu_header_counts(path):
    """(NumberOfPoints, NumberOfCells) from the XML header of a .vtu."""
    try:
        with open(path, "rb") as f:
            head = f.read(8192).decode("latin-1")
    except OSError:
        return None, None
    mp = re.search(r'NumberOfPoints="\s*(\d+)', head)
    mc = re.search(r'NumberOfCells="\s*(\d+)', head)
    return (int(mp.group(1)) if mp else None, int(mc.group(1)) if mc else None)


def fmt_num(x):
    if x is None:
        return "inf"
    if float(x).is_integer():
        return str(int(x))
    return repr(float(x))


def interval_str(iv):
    a, b = iv
    lo = "(-inf" if a is None else "[" + fmt_num(a)
    hi = "inf)" if b is None else fmt_num(b) + "]"
    return lo + ", " + hi


VTU_ENCODING = "base64"   # set from --vtu-encoding in main()


def tptd_cmd(binary, inp, out, iv, method, threads, report):
    a, b = iv
    cmd = [binary, inp, "-o", out]
    # --alpha=VALUE form so that negative numbers are never taken for flags
    cmd.append("--alpha=" + ("-inf" if a is None else fmt_num(a)))
    if b is not None:
        cmd.append("--beta=" + fmt_num(b))
    cmd += ["--method", method, "-j", str(threads), "--report", report, "--no-analysis",
            "--vtu-encoding", VTU_ENCODING]
    return cmd


def vtk_cmd(inp, out, iv):
    a, b = iv
    cmd = [sys.executable, os.path.join(HERE, "vtk_peer.py"), "mesh", inp, out]
    if a is not None:
        cmd += ["--alpha", fmt_num(a)]
    if b is not None:
        cmd += ["--beta", fmt_num(b)]
    return cmd


def find_key(d, names):
    """First numeric value for any of `names`, searching nested dicts."""
    if not isinstance(d, dict):
        return None
    for n in names:
        if n in d and isinstance(d[n], (int, float)) and not isinstance(d[n], bool):
            return d[n]
    for v in d.values():
        if isinstance(v, dict):
            r = find_key(v, names)
            if r is not None:
                return r
    return None


# ----------------------------------------------------------------------------
# one benchmark cell (dataset x interval x method x threads), R repetitions
# ----------------------------------------------------------------------------

def bench(label, make_cmd, out_vtu, reps, timeout, log_dir, report_path=None):
    """R repetitions; the last repetition's .vtu is left in place (caller removes it)."""
    runs = []
    for r in range(reps):
        for p in (out_vtu, report_path):
            if p and os.path.exists(p):
                os.remove(p)
        cmd = make_cmd()
        res = run_measured(cmd, os.path.join(log_dir, f"{label}.rep{r}"), timeout=timeout)
        res["cmd"] = cmd
        res["vtu_bytes"] = os.path.getsize(out_vtu) if os.path.exists(out_vtu) else None
        res["vtu_points"], res["vtu_cells"] = vtu_header_counts(out_vtu)
        res["report"] = None
        if report_path and os.path.exists(report_path):
            try:
                with open(report_path) as f:
                    res["report"] = json.load(f)
            except Exception as e:  # noqa: BLE001
                res["report"] = {"_parse_error": str(e)}
        if res["rc"] == 0 and report_path is None:
            # VTK peer prints one JSON line
            try:
                res["report"] = json.loads(res["stdout"].strip().splitlines()[-1])
            except Exception:  # noqa: BLE001
                pass
        status = "ok" if res["rc"] == 0 and res["vtu_bytes"] else f"FAILED rc={res['rc']}"
        print(f"    rep {r + 1}/{reps}: {res['wall']:8.3f} s  {res['maxrss_kb'] / 1024:8.1f} MB  "
              f"tets={res['vtu_cells']}  {status}", flush=True)
        if status != "ok":
            tail = (res["stderr"] or res["stdout"]).strip().splitlines()[-5:]
            for line in tail:
                print("      | " + line)
        runs.append(res)
    ok = [x for x in runs if x["rc"] == 0 and x["vtu_bytes"]]
    if not ok:
        return {"ok": False, "runs": runs, "error": (runs[-1]["stderr"] or "")[-2000:]}
    walls = [x["wall"] for x in ok]
    med = statistics.median(walls)
    pick = min(ok, key=lambda x: abs(x["wall"] - med))
    return {"ok": True, "runs": runs, "wall": med, "walls": walls,
            "maxrss_kb": pick["maxrss_kb"], "maxrss_kb_all": [x["maxrss_kb"] for x in ok],
            "vtu_bytes": pick["vtu_bytes"], "vtu_cells": pick["vtu_cells"],
            "vtu_points": pick["vtu_points"], "report": pick["report"],
            "cmd": pick["cmd"], "user": pick["user"], "sys": pick["sys"]}


def count_inverted(vtu):
    res = subprocess.run([sys.executable, os.path.join(HERE, "vtk_peer.py"), "inverted", vtu],
                         capture_output=True, text=True)
    if res.returncode != 0:
        return {"error": res.stderr[-1000:]}
    return json.loads(res.stdout.strip().splitlines()[-1])


# ----------------------------------------------------------------------------
# machine description
# ----------------------------------------------------------------------------

def sh(cmd):
    try:
        return subprocess.run(cmd, shell=True, capture_output=True, text=True, timeout=30).stdout.strip()
    except Exception as e:  # noqa: BLE001
        return f"({e})"


def machine_info():
    info = {
        "date": datetime.datetime.now().isoformat(timespec="seconds"),
        "hostname": platform.node(),
        "uname": sh("uname -srmv"),
        "nproc": os.cpu_count(),
        "lscpu": sh("lscpu"),
        "free_g": sh("free -g"),
        "python": sys.version.split()[0],
        "rustc": sh("rustc -V"),
        "git_head": sh(f"git -C {shlex.quote(REPO)} rev-parse --short HEAD"),
        "git_dirty": bool(sh(f"git -C {shlex.quote(REPO)} status --porcelain --untracked-files=no")),
    }
    # versions via a child process: importing vtk/numpy here would inflate the harness's RSS,
    # which leaks into the children's ru_maxrss when /usr/bin/time is unavailable
    info["vtk"] = sh(f"{shlex.quote(sys.executable)} -c 'import vtk; print(vtk.vtkVersion.GetVTKVersion())'") or None
    info["numpy"] = sh(f"{shlex.quote(sys.executable)} -c 'import numpy; print(numpy.__version__)'") or None
    info["rss_source"] = "/usr/bin/time -v" if HAVE_GNU_TIME else "os.wait4 ru_maxrss (upper bound; install GNU time)"
    return info


def loadavg():
    try:
        return os.getloadavg()
    except OSError:
        return None


# ----------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="128,256", help="noisy cube sizes (default 128,256)")
    ap.add_argument("--quick", action="store_true", help="64^3 + MNI WM only, 1 rep")
    ap.add_argument("--reps", type=int, default=None, help="repetitions per cell, median reported (default 3; 1 with --quick)")
    ap.add_argument("--threads", default="1,2", help="thread counts for tptd-mesh -j (default 1,2)")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--datasets", default=None, help="comma-separated dataset names to keep (default: all selected)")
    ap.add_argument("--no-mri", action="store_true", help="skip the MNI volumes")
    ap.add_argument("--no-vtk", action="store_true", help="skip the VTK peer")
    ap.add_argument("--bin", default=os.environ.get("TPTD_BIN", os.path.join(REPO, "target", "release", "tptd-mesh")),
                    help="tptd-mesh binary (default $TPTD_BIN or target/release/tptd-mesh)")
    ap.add_argument("--timeout", type=float, default=1800.0, help="per-run timeout, seconds")
    ap.add_argument("--keep-outputs", action="store_true", help="keep the .vtu files in benchmarks/out/")
    ap.add_argument("--vtu-encoding", default="base64", choices=["base64", "zlib", "raw"],
                    help="tptd-mesh --vtu-encoding (default base64, the binary's default; the "
                         "README's table was measured with raw)")
    ap.add_argument("--out", default=None,
                    help="results path prefix; writes PREFIX.md and PREFIX.json "
                         "(default benchmarks/results, or benchmarks/results_quick with --quick)")
    args = ap.parse_args()
    global VTU_ENCODING
    VTU_ENCODING = args.vtu_encoding

    reps = args.reps if args.reps is not None else (1 if args.quick else 3)
    if args.out is None:
        args.out = os.path.join(HERE, "results_quick" if args.quick else "results")
    sizes = [64] if args.quick else [int(s) for s in args.sizes.split(",") if s.strip()]
    threads = [int(t) for t in args.threads.split(",") if t.strip()]
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    command = "python3 " + " ".join(shlex.quote(a) for a in [os.path.relpath(sys.argv[0], REPO)] + sys.argv[1:])

    if not HAVE_GNU_TIME:
        print("[run] WARNING: /usr/bin/time not found (apt-get install time); peak RSS falls back to "
              "os.wait4 ru_maxrss, which includes the harness's own RSS at fork time", flush=True)
    if not (os.path.isfile(args.bin) and os.access(args.bin, os.X_OK)):
        sys.exit(f"tptd-mesh binary not found: {args.bin}\n  build it: cargo build --release   (or pass --bin / TPTD_BIN)")

    # ---- datasets ---------------------------------------------------------
    man_path = os.path.join(DATA, "manifest.json")
    need = [f"noisy_{n}" for n in sizes]
    manifest = {}
    if os.path.exists(man_path):
        with open(man_path) as f:
            manifest = json.load(f).get("datasets", {})
    missing = [n for n in need if n not in manifest or not os.path.exists(manifest[n]["path"])]
    if missing or (not args.no_mri and "mni_wm" not in manifest):
        print(f"[run] generating data for {missing or 'MNI'} via make_data.py", flush=True)
        subprocess.run([sys.executable, os.path.join(HERE, "make_data.py"), "--sizes", ",".join(str(s) for s in sizes)],
                       check=True)
        with open(man_path) as f:
            manifest = json.load(f)["datasets"]
    names = list(need)
    if not args.no_mri:
        names += ["mni_wm"] if args.quick else ["mni_t1", "mni_wm"]
    if args.datasets:
        keep = set(args.datasets.split(","))
        names = [n for n in names if n in keep]
    names = [n for n in names if n in manifest]

    os.makedirs(OUT, exist_ok=True)
    log_dir = os.path.join(OUT, "logs")
    os.makedirs(log_dir, exist_ok=True)

    machine = machine_info()
    machine["loadavg_start"] = loadavg()
    print(f"[run] {machine['date']}  {machine['nproc']} CPUs  load {machine['loadavg_start']}  "
          f"git {machine['git_head']}{' (dirty)' if machine['git_dirty'] else ''}  VTK {machine['vtk']}")
    print(f"[run] binary {args.bin}; reps {reps}; threads {threads}; methods {methods}; datasets {names}", flush=True)

    rows = []
    quality = []
    t_start = time.perf_counter()
    for name in names:
        ds = manifest[name]
        inp = ds["path"]
        voxels = int(ds["voxels"])
        nx, ny, nz = ds["shape"]
        cells_grid = (nx - 1) * (ny - 1) * (nz - 1)
        for iv in ds["intervals"]:
            iv = (iv[0], iv[1])
            two_sided = iv[0] is not None and iv[1] is not None
            ivs = interval_str(iv)
            tag = f"{name}_{'2s' if two_sided else '1s'}"
            print(f"\n[run] {name} {tuple(ds['shape'])}  interval {ivs}", flush=True)
            group = []
            for method in methods:
                for j in threads:
                    label = f"{tag}_{method}_j{j}"
                    out_vtu = os.path.join(OUT, label + ".vtu")
                    rep_json = os.path.join(OUT, label + ".report.json")
                    print(f"  tptd-mesh --method {method} -j {j}", flush=True)
                    b = bench(label, lambda: tptd_cmd(args.bin, inp, out_vtu, iv, method, j, rep_json),
                              out_vtu, reps, args.timeout, log_dir, rep_json)
                    row = {"dataset": name, "shape": ds["shape"], "interval": ivs, "interval_values": list(iv),
                           "method": method, "threads": j, "tool": "tptd-mesh", **b}
                    if b["ok"] and two_sided and method == "ctd" and j == threads[0]:
                        q = count_inverted(out_vtu)
                        q.update({"dataset": name, "interval": ivs, "method": "ctd", "threads": j})
                        quality.append(q)
                    if b["ok"] and not args.keep_outputs and os.path.exists(out_vtu):
                        os.remove(out_vtu)
                    row["voxels"] = voxels
                    row["cells_grid"] = cells_grid
                    group.append(row)
            if not args.no_vtk:
                label = f"{tag}_vtk_j1"
                out_vtu = os.path.join(OUT, label + ".vtu")
                print("  VTK peer (vtkClipVolume, tets only)", flush=True)
                b = bench(label, lambda: vtk_cmd(inp, out_vtu, iv), out_vtu, reps, args.timeout, log_dir)
                row = {"dataset": name, "shape": ds["shape"], "interval": ivs, "interval_values": list(iv),
                       "method": "vtk", "threads": 1, "tool": "vtk_peer.py", **b,
                       "voxels": voxels, "cells_grid": cells_grid}
                if b["ok"] and two_sided:
                    q = count_inverted(out_vtu)
                    q.update({"dataset": name, "interval": ivs, "method": "vtk", "threads": 1})
                    quality.append(q)
                    print(f"    VTK inverted tets: {q.get('negative')} of {q.get('tets')}", flush=True)
                if not args.keep_outputs and os.path.exists(out_vtu):
                    os.remove(out_vtu)
                group.append(row)
            derive(group)
            rows.extend(group)

    machine["loadavg_end"] = loadavg()
    total = time.perf_counter() - t_start
    checks = evaluate(rows, threads)
    print("\n[run] targets")
    for c in checks:
        print(c["line"])
    payload = {"command": command, "cwd_note": "run from the repository root", "reps": reps,
               "machine": machine, "binary": args.bin, "total_seconds": total,
               "targets": {"ctd_over_vtk_tets_per_s_min": TARGET_CTD_OVER_VTK,
                           "tptd_over_six_s_per_tet_max": TARGET_TPTD_OVER_SIX,
                           "rss_over_io_max": TARGET_RSS_OVER_IO},
               "datasets": {n: manifest[n] for n in names},
               "rows": [strip_row(r) for r in rows], "quality": quality, "checks": checks}
    with open(args.out + ".json", "w") as f:
        json.dump(payload, f, indent=1)
    with open(args.out + ".md", "w") as f:
        f.write(render_md(payload))
    print(f"\n[run] wrote {args.out}.md and {args.out}.json  ({total:.0f} s)")


def derive(group):
    """Per-row throughput / memory metrics and the ratios inside one (dataset, interval) group."""
    for r in group:
        if not r["ok"]:
            continue
        rep = r.get("report") or {}
        cells = find_key(rep, ["cells_total", "cells"]) if r["tool"] == "tptd-mesh" else None
        r["cells"] = int(cells) if cells else r["cells_grid"]
        tets = r["vtu_cells"]
        if tets is None:
            tets = find_key(rep, ["tets", "cells_out"])
        r["tets"] = tets
        r["cells_per_s"] = r["cells"] / r["wall"]
        r["tets_per_s"] = tets / r["wall"] if tets else None
        r["s_per_tet"] = r["wall"] / tets if tets else None
        r["rss_mb"] = r["maxrss_kb"] / 1024.0
        io_bytes = 8.0 * r["voxels"] + (r["vtu_bytes"] or 0)
        r["io_mb"] = io_bytes / 2 ** 20
        r["rss_over_io"] = r["maxrss_kb"] * 1024.0 / io_bytes
    vtk = next((r for r in group if r["method"] == "vtk" and r["ok"]), None)
    for r in group:
        if not r["ok"]:
            continue
        if r["method"] == "ctd" and vtk and vtk.get("tets_per_s") and r.get("tets_per_s"):
            r["ctd_over_vtk"] = r["tets_per_s"] / vtk["tets_per_s"]
        if r["method"] == "tptd":
            six = next((x for x in group if x["method"] == "six" and x["threads"] == r["threads"] and x["ok"]), None)
            if six and six.get("s_per_tet") and r.get("s_per_tet"):
                r["tptd_over_six"] = r["s_per_tet"] / six["s_per_tet"]


def evaluate(rows, threads):
    checks = []

    def add(name, ok, detail):
        status = "N/A " if ok is None else ("PASS" if ok else "FAIL")
        checks.append({"target": name, "status": status.strip(), "detail": detail,
                       "line": f"{status} {name}: {detail}"})

    for j in threads:
        vals = [(r["dataset"], r["interval"], r["ctd_over_vtk"]) for r in rows
                if r["method"] == "ctd" and r["threads"] == j and r.get("ctd_over_vtk") is not None]
        if vals:
            worst = min(vals, key=lambda v: v[2])
            add(f"ctd tets/s >= {TARGET_CTD_OVER_VTK:g}x VTK tets/s (ctd -j {j})", worst[2] >= TARGET_CTD_OVER_VTK,
                f"min {worst[2]:.2f}x ({worst[0]} {worst[1]}); all: "
                + ", ".join(f"{d} {i} {v:.2f}x" for d, i, v in vals))
        else:
            add(f"ctd tets/s >= {TARGET_CTD_OVER_VTK:g}x VTK tets/s (ctd -j {j})", None, "no data")
        vals = [(r["dataset"], r["interval"], r["tptd_over_six"]) for r in rows
                if r["method"] == "tptd" and r["threads"] == j and r.get("tptd_over_six") is not None]
        if vals:
            worst = max(vals, key=lambda v: v[2])
            add(f"tptd s/tet <= {TARGET_TPTD_OVER_SIX:g}x six s/tet (-j {j})", worst[2] <= TARGET_TPTD_OVER_SIX,
                f"max {worst[2]:.2f}x ({worst[0]} {worst[1]}); all: "
                + ", ".join(f"{d} {i} {v:.2f}x" for d, i, v in vals))
        else:
            add(f"tptd s/tet <= {TARGET_TPTD_OVER_SIX:g}x six s/tet (-j {j})", None, "no data")
    all_runs = [r for r in rows if r["tool"] == "tptd-mesh" and r["ok"]]
    big = [r for r in all_runs if r["voxels"] >= RSS_MIN_VOXELS]
    name = f"peak RSS <= {TARGET_RSS_OVER_IO:g}x (8 B x voxels + .vtu bytes)"
    for vals, scope, informative in ((big, f"tptd-mesh runs with >= {RSS_MIN_VOXELS:,} voxels", False),
                                     (all_runs, "all tptd-mesh runs, incl. small inputs where the "
                                                "process baseline (~10-25 MB) dominates", True)):
        if not vals:
            if not informative:
                add(f"{name} ({scope})", None, "no data")
            continue
        worst = max(vals, key=lambda r: r["rss_over_io"])
        detail = (f"max {worst['rss_over_io']:.2f}x ({worst['dataset']} {worst['interval']} {worst['method']} "
                  f"-j {worst['threads']}: {worst['rss_mb']:.0f} MB vs {worst['io_mb']:.0f} MB)")
        if informative:
            ok = worst["rss_over_io"] <= TARGET_RSS_OVER_IO
            checks.append({"target": f"{name} ({scope})", "status": "INFO", "detail": detail,
                           "line": f"INFO {name} ({scope}): {'within' if ok else 'above'} target, {detail}"})
        else:
            add(f"{name} ({scope})", worst["rss_over_io"] <= TARGET_RSS_OVER_IO, detail)
    failed = [r for r in rows if not r["ok"]]
    if failed:
        add("all runs succeeded", False, ", ".join(f"{r['dataset']} {r['interval']} {r['method']} -j {r['threads']}"
                                                   for r in failed))
    else:
        add("all runs succeeded", True, f"{len(rows)} rows")
    return checks


def strip_row(r):
    out = {k: v for k, v in r.items() if k != "runs"}
    out["reps"] = [{k: x[k] for k in ("wall", "maxrss_kb", "rss_source", "rc", "user", "sys", "vtu_bytes", "vtu_cells")}
                   for x in r.get("runs", [])]
    if not r["ok"]:
        out["stderr_tail"] = (r["runs"][-1]["stderr"] or "")[-2000:] if r.get("runs") else ""
    return out


def f2(x, fmt):
    return "–" if x is None else format(x, fmt)


def render_md(p):
    m = p["machine"]
    L = []
    L.append("# tptd-mesh benchmark results\n")
    L.append(f"Generated {m['date']} by `benchmarks/run.py` (git `{m['git_head']}`"
             f"{', dirty tree' if m['git_dirty'] else ''}), {p['reps']} repetition(s) per row, median wall time.\n")
    L.append("Command (from the repository root):\n")
    L.append("```\npython3 benchmarks/make_data.py" + (" --quick" if "--quick" in p["command"] else "")
             + "\n" + p["command"] + "\n```\n")
    la0, la1 = m.get("loadavg_start"), m.get("loadavg_end")
    if la0 and la0[0] > 0.5 * (m.get("nproc") or 1):
        L.append(f"> **Provisional**: the machine was busy (load average {la0[0]:.2f} at start, "
                 f"{la1[0] if la1 else float('nan'):.2f} at end on {m['nproc']} CPUs); rerun on an idle machine for "
                 "numbers to quote.\n")
    L.append("## Results\n")
    L.append("End to end per fresh process: start → read → mesh → binary .vtu written. "
             "`cells` = grid cells; `tets` = tetrahedra in the written .vtu; "
             "`RSS/IO` = peak RSS ÷ (8 B × voxels + .vtu bytes); "
             "`ctd/VTK` = ctd output tets/s ÷ VTK output tets/s; "
             "`tptd/six` = tptd seconds per output tet ÷ six seconds per output tet (same -j).\n")
    L.append("| dataset | interval | method | -j | cells | tets | wall s | Mcells/s | Mtets/s | peak RSS MB | .vtu MB | RSS/IO | ctd/VTK | tptd/six |")
    L.append("|---|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|")
    for r in p["rows"]:
        if not r["ok"]:
            L.append(f"| {r['dataset']} | {r['interval']} | {r['method']} | {r['threads']} | FAILED | | | | | | | | | |")
            continue
        L.append("| " + " | ".join([
            r["dataset"], r["interval"], ("**VTK**" if r["method"] == "vtk" else r["method"]), str(r["threads"]),
            f"{r['cells']:,}", f"{r['tets']:,}" if r["tets"] is not None else "–", f"{r['wall']:.3f}",
            f"{r['cells_per_s'] / 1e6:.2f}", f2(r["tets_per_s"] and r["tets_per_s"] / 1e6, ".3f"),
            f"{r['rss_mb']:.0f}", f"{(r['vtu_bytes'] or 0) / 2 ** 20:.1f}", f"{r['rss_over_io']:.2f}",
            f2(r.get("ctd_over_vtk"), ".2f"), f2(r.get("tptd_over_six"), ".2f")]) + " |")
    L.append("")
    L.append("## Targets\n")
    L.append("```")
    for c in p["checks"]:
        L.append(c["line"])
    L.append("```\n")
    if p["quality"]:
        L.append("## Quality note: inverted tetrahedra (two-sided intervals)\n")
        L.append("Signed volume < 0 with VTK's orientation convention, counted with numpy on the written .vtu "
                 "(`vtk_peer.py inverted`). VTK's second clip (vtkClipDataSet) emits wedges; "
                 "vtkDataSetTriangleFilter splits them into tets, which is where inverted tets come from.\n")
        L.append("| dataset | interval | mesh | tets | negative volume | < -1e-6 voxel³ | zero volume |")
        L.append("|---|---|---|--:|--:|--:|--:|")
        for q in p["quality"]:
            if "error" in q:
                L.append(f"| {q['dataset']} | {q['interval']} | {q['method']} | error | | | |")
                continue
            L.append(f"| {q['dataset']} | {q['interval']} | {q['method']} -j {q['threads']} | {q['tets']:,} | "
                     f"{q['negative']:,} ({100.0 * q['negative'] / max(q['tets'], 1):.1f}%) | "
                     f"{q['negative_gt_1e-6']:,} | {q['zero']:,} |")
        L.append("")
    # stage timings
    L.append("## Internal stage timings (median-time repetition)\n")
    L.append("From tptd-mesh `--report` JSON and the VTK peer's own JSON line (seconds).\n")
    L.append("| dataset | interval | method | -j | timings; cells meshed and cells per decomposition case (tptd-mesh) |")
    L.append("|---|---|---|--:|---|")
    for r in p["rows"]:
        if not r["ok"]:
            continue
        rep = r.get("report") or {}
        t = (rep.get("timings_seconds") or rep.get("timings") or rep.get("timing")
             or {k: v for k, v in rep.items() if "time" in k or k.endswith("_s")})
        t = {k: (round(v, 4) if isinstance(v, float) else v) for k, v in t.items()}
        st = t.pop("stages", None)
        if isinstance(st, dict):
            t.update({k: (round(v, 4) if isinstance(v, float) else v) for k, v in st.items()})
        extra = ""
        cases = rep.get("cells_by_case")
        if isinstance(cases, dict):
            extra = " cases " + " ".join(f"{k}:{v.get('count') if isinstance(v, dict) else v}" for k, v in cases.items())
            if rep.get("cells_meshed") is not None:
                extra = f" meshed {rep['cells_meshed']:,};" + extra
        L.append(f"| {r['dataset']} | {r['interval']} | {r['method']} | {r['threads']} | "
                 f"`{json.dumps(t, separators=(',', ':'), default=str)[:400]}`{extra} |")
    L.append("")
    L.append("## Datasets\n")
    for n, d in p["datasets"].items():
        L.append(f"- `{n}` {'×'.join(map(str, d['shape']))} {d['dtype']}: {d['note']}  \n  "
                 f"intervals: {', '.join(interval_str(tuple(iv)) for iv in d['intervals'])}")
    L.append("")
    L.append("## Machine\n")
    L.append(f"{m['uname']}; Python {m['python']}; {m['rustc']}; VTK {m['vtk']}; numpy {m.get('numpy')}; "
             f"peak RSS from {m.get('rss_source')}; "
             f"load average start {m.get('loadavg_start')}, end {m.get('loadavg_end')}; total harness time "
             f"{p['total_seconds']:.0f} s.\n")
    L.append("```\n$ lscpu\n" + m["lscpu"] + "\n\n$ free -g\n" + m["free_g"] + "\n```\n")
    return "\n".join(L)


if __name__ == "__main__":
    main()
