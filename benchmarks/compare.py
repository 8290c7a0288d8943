#!/usr/bin/env python3
"""Peer comparison report: tptd-mesh (ctd, ctd --quality) against TetGen, fTetWild, CGAL
Mesh_3 and MMG3D, every mesh judged by our checker. One command regenerates
benchmarks/report/report.md and the PNG plots next to it:

  python3 benchmarks/compare.py                      # the report (about 30 min on 2 shared cores)
  python3 benchmarks/compare.py --quick              # smoke run: 24^3, two domains, no full MNI
  python3 benchmarks/compare.py --domains torus,shell --size 32 --out /tmp/r   # a subset elsewhere

Domains: those of tests/py/compare_peers.py (torus, genus 3, two balls 0.3 voxel apart, thin
shell, seeded random field, MNI152 white-matter crop) at --size (default 48^3; the test uses
20^3-24^3), a T1 grey-matter-band crop of the same size, and the full nilearn MNI152 volumes
(197x233x189 uint8): T1 at {f >= 127.0239} and in [151.0135, 201.0135], white matter at
{f >= 127.0135} and {f >= 63.0338}. Levels on uint8 data are never integers nor k + 0.5, and
none is within 0.005 of a critical value of the trilinear field or a face saddle (tptd-mesh
warns about such bounds and names safer ones; 127.0239 and 63.0338 are the ones it names next
to 127.0135 and 63.0135, which are near critical values of the whole T1 and white-matter
volumes).

Tools, each a fresh child process under a time limit (a crash, failure or timeout is a row,
never an exception; runs that would start after --budget seconds are recorded `skipped`):
  ctd            `tptd-mesh VOL [--alpha A] [--beta B] -o ctd.msh --msh-version 4.1-binary -j 1`
                 (one thread, like every peer here)
  ctd --quality  the same with --quality
  TetGen         PyPI `tetgen`, switches `pq1.2`, on the boundary of our ctd --quality mesh
                 (the worker of tests/py/compare_peers.py)
  fTetWild       PyPI `pytetwild` on the same surface (compare_peers.py's settings)
  CGAL Mesh_3    Debian python3-pygalmesh under /usr/bin/python3 (this script as --worker):
                 `generate_from_array(labels, (1, 1, 1), ...)` on the uint8 image "voxel in
                 the interval" (CGAL meshes a labelled image, not a level set)
  MMG3D          `mmg3d_O3 -optim -noinsert -hausd 0.01` (PyPI mmgpy) on our plain ctd mesh
                 written as medit .mesh
Times: ours = process wall (reading the volume, writing the mesh); TetGen, fTetWild, CGAL =
the library call only; MMG3D = the mmg3d_O3 process.

Every mesh is judged by `tptd-mesh --inspect MESH... --volume VOL --alpha A [--beta B] --json
J` (compare_peers.inspect): validity, problems, Betti numbers against the trilinear
interval's, dihedral extremes and histogram, distance of the boundary to the level sets.

Outputs: benchmarks/report/{report.md, *.png} (committed); volumes, meshes, logs and
results.json (every number, with the dihedral histograms) under benchmarks/out/compare/
(git-ignored).
"""
import argparse
import datetime
import json
import os
import platform
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(REPO, "tests", "py"))

import quality as q          # noqa: E402  (domains, mesh I/O, child processes)
import compare_peers as cp   # noqa: E402  (the test's domains, surfaces, peer worker, checker)

REPORT = os.path.join(HERE, "report")
OUT = os.path.join(HERE, "out", "compare")
DEBIAN_PYTHON = "/usr/bin/python3"      # python3-pygalmesh is installed for this one only
MMG_BIN = "mmg3d_O3"
MMG_ARGS = ["-optim", "-noinsert", "-hausd", "0.01"]
TETGEN_SWITCHES = "pq1.2"
# CGAL Mesh_3 criteria in voxels: fine enough to follow one-voxel features, coarse inside
CGAL = dict(max_facet_distance=0.2, max_radius_surface_delaunay_ball=1.5, min_facet_angle=25.0,
            max_cell_circumradius=2.0, max_circumradius_edge_ratio=3.0, perturb=True, exude=True,
            seed=0)
T1_BAND = (151.0135, 201.0135)
T1_LEVEL = 127.0239     # 127.0135 is within 0.003 of critical values of the whole T1
WM_LOW_LEVEL = 63.0338  # 63.0135 is within 0.003 of critical values of the whole WM map
TOOLS = ["ctd", "ctd --quality", "TetGen -pq1.2", "fTetWild", "CGAL Mesh_3", "MMG3D -optim"]
COLORS = dict(zip(TOOLS, ["#1f77b4", "#08306b", "#2ca02c", "#ff7f0e", "#9467bd", "#d62728"]))


# ----------------------------------------------------------------------------
# domains: name -> (volume, alpha, beta, note); the test's builders at larger sizes
# ----------------------------------------------------------------------------

def mni_full(fname, alpha, beta, what):
    a, _ = q.mri_crop(fname, 10 ** 6)       # a crop larger than the volume: all of it
    return a, alpha, beta, f"MNI152 2009a {what} (uint8), whole volume {'x'.join(map(str, a.shape))}"


def mni_t1_crop(n):
    a, lo = q.mri_crop(q.T1_NAME, n)
    return a, T1_BAND[0], T1_BAND[1], f"MNI152 2009a T1 (uint8), {n}^3 crop at {lo}, grey-matter band"


def domains(args):
    """[(name, builder, full)]: `full` marks a whole MNI volume (its own peer time limit)."""
    n, c = args.size, args.mni_crop
    out = [("torus", lambda: cp.dom_torus(n), False),
           ("genus3", lambda: cp.dom_genus3(n), False),
           ("two_spheres", lambda: cp.dom_two_spheres(n), False),
           ("shell", lambda: cp.dom_shell(n), False),
           ("random", lambda: cp.dom_random(n), False),
           ("mni_wm_crop", lambda: cp.dom_mni(c), False),
           ("mni_t1_crop", lambda: mni_t1_crop(c), False)]
    if not args.no_full:
        out += [("mni_t1_127", lambda: mni_full(q.T1_NAME, T1_LEVEL, None, f"T1, {{f >= {T1_LEVEL}}}"), True),
                ("mni_t1_band", lambda: mni_full(q.T1_NAME, *T1_BAND, "T1, grey-matter band"), True),
                ("mni_wm_127", lambda: mni_full(q.WM_NAME, cp.MNI_LEVEL, None, "white matter, {f >= 127.0135}"), True),
                ("mni_wm_63", lambda: mni_full(q.WM_NAME, WM_LOW_LEVEL, None,
                                                      f"white matter, {{f >= {WM_LOW_LEVEL}}}"), True)]
    wanted = args.domains.split(",") if args.domains else None
    return [d for d in out if wanted is None or d[0] in wanted]


# ----------------------------------------------------------------------------
# child-process workers (this script with --worker)
# ----------------------------------------------------------------------------

def cgal_worker(vol, prefix, alpha, beta):
    """Under Debian's python3: CGAL Mesh_3 (pygalmesh) on the label image of the interval;
    writes prefix.node/.ele and prefix.seconds."""
    import pygalmesh
    f = np.load(vol)
    inside = np.ones(f.shape, dtype=bool)
    if alpha != "-":
        inside &= f >= float(alpha)
    if beta != "-":
        inside &= f <= float(beta)
    labels = np.ascontiguousarray(inside.astype(np.uint8))
    t0 = time.perf_counter()
    m = pygalmesh.generate_from_array(labels, (1.0, 1.0, 1.0), verbose=False, **CGAL)
    seconds = time.perf_counter() - t0
    T = np.concatenate([c.data for c in m.cells if c.type == "tetra"])
    if len(T) == 0:
        sys.exit("no tetrahedra")
    cp.write_tetgen_files(prefix, np.asarray(m.points, dtype=np.float64), T)
    with open(prefix + ".seconds", "w") as fs:
        fs.write(repr(seconds))


def write_medit(path, P, T):
    """Medit ASCII .mesh with vertices and tets only (1-based; MMG builds the boundary). The
    format is free (blanks or line ends between numbers): each table is written in one go."""
    with open(path, "w") as f:
        f.write(f"MeshVersionFormatted 2\nDimension 3\nVertices\n{len(P)}\n")
        np.column_stack([P, np.zeros(len(P))]).tofile(f, sep=" ", format="%.17g")
        f.write(f"\nTetrahedra\n{len(T)}\n")
        np.column_stack([T + 1, np.ones(len(T), dtype=np.int64)]).tofile(f, sep=" ", format="%d")
        f.write("\nEnd\n")


def mmg_binary():
    """mmgpy's mmg3d_O3 executable (its console script is a Python wrapper: skip that)."""
    try:
        import mmgpy
        exe = os.path.join(os.path.dirname(mmgpy.__file__), "bin", MMG_BIN)
        if os.path.exists(exe):
            return exe
    except ImportError:
        pass
    return shutil.which(MMG_BIN) or MMG_BIN


# ----------------------------------------------------------------------------
# runs
# ----------------------------------------------------------------------------

def ours_warnings(prefix):
    """tptd-mesh's warnings of one run (stderr lines), the file path cut out, each shortened."""
    try:
        with open(prefix + ".stderr", errors="replace") as f:
            lines = [l.strip() for l in f if "warning:" in l]
    except OSError:
        return []
    return [l.split(".npy: ", 1)[-1][:260] for l in lines]


def boundary_from_file(msh):
    """Our mesh's boundary surface, outward: the labelled boundary triangles our .msh carries
    (alpha, beta and box groups: the checker requires them to be exactly the boundary faces);
    compare_peers.our_surface (faces of one tet) when the file has none. Reading them is
    minutes faster than finding the faces of one tet on the whole MNI volumes."""
    import meshio
    m = meshio.read(msh)
    tris = [c.data for c in m.cells if c.type == "triangle"]
    if not tris:
        return cp.our_surface(msh)
    used, F = np.unique(np.concatenate(tris).astype(np.int64), return_inverse=True)
    V = np.asarray(m.points, dtype=np.float64)[used]
    F = F.reshape(-1, 3)
    return V, cp.orient_outward(V, F)


def run_ours(args, dom):
    """run_domain, with a Python error in this script recorded in the domain's rows (the
    other domains go on)."""
    try:
        return run_domain(args, dom)
    except Exception as e:      # noqa: BLE001  (one domain's error must not end the report)
        dom.setdefault("rows", []).append({"tool": "compare.py", "status": "error", "wall": 0.0,
                                           "detail": f"{type(e).__name__}: {e}"[:300]})
        for k, v in (("shape", []), ("dtype", "?"), ("alpha", None), ("beta", None), ("note", "error"),
                     ("bounds", []), ("meshes", []), ("jobs", []), ("vol", os.path.join(args.work, dom["name"]))):
            dom.setdefault(k, v)
        print(f"[compare] {dom['name']}: ERROR {e}", flush=True)
        return dom


def run_domain(args, dom):
    """ctd and ctd --quality on one domain; then the surface and the peer jobs."""
    f, alpha, beta, note = dom["build"]()
    d = os.path.join(args.work, dom["name"])
    os.makedirs(d, exist_ok=True)
    vol = os.path.join(d, "vol.npy")
    np.save(vol, np.ascontiguousarray(f))
    b = cp.bounds_args(alpha, beta)
    dom.update(shape=list(f.shape), dtype=str(f.dtype), alpha=alpha, beta=beta, note=note, vol=vol,
               bounds=b, rows=[], meshes=[], jobs=[])
    del f
    for tool, extra, name in (("ctd", [], "ctd.msh"), ("ctd --quality", ["--quality"], "ctd_quality.msh")):
        out = os.path.join(d, name)
        cmd = [args.bin, vol, *b, "-o", out, "--msh-version", "4.1-binary", "-j", "1", "-q", *extra]
        r = q.run_child(cmd, out[:-4], args.ours_timeout)
        row = {"tool": tool, "command": " ".join(cmd), **r, "warnings": ours_warnings(out[:-4])}
        dom["rows"].append(row)
        if r["status"] == "ok":
            dom["meshes"].append((row, out))
    ok = {r["tool"]: m for r, m in dom["meshes"]}
    src = ok.get("ctd --quality") or ok.get("ctd")
    limit = args.full_peer_timeout if dom["full"] else args.peer_timeout

    def job(tool, cmd, prefix, mesh_ext, pending=None):
        row = {"tool": tool, "command": " ".join(cmd)}
        dom["rows"].append(row)
        if pending:
            row.update(status="not run", wall=0.0, detail=pending)
        else:
            dom["jobs"].append((row, cmd, prefix, d, limit, mesh_ext))

    me = os.path.abspath(__file__)
    if src:
        V, F = boundary_from_file(src)
        holes = q.cavity_hole_points(V, F, local=True)[0]
        npz = os.path.join(d, "surf_ours.npz")
        np.savez(npz, V=V, F=F, holes=holes)
        dom["surface"] = {"from": os.path.basename(src), "triangles": int(len(F)), "holes": int(len(holes))}
        worker = os.path.join(REPO, "tests", "py", "compare_peers.py")
        job("TetGen -pq1.2", [sys.executable, worker, "--worker", "tetgen", npz, os.path.join(d, "tetgen"),
                              TETGEN_SWITCHES], os.path.join(d, "tetgen"), ".node")
        job("fTetWild", [sys.executable, worker, "--worker", "ftetwild", npz, os.path.join(d, "ftetwild"),
                         repr(cp.FTETWILD_EDGE)], os.path.join(d, "ftetwild"), ".node")
    else:
        for tool in ("TetGen -pq1.2", "fTetWild"):
            job(tool, [], None, None, pending="no mesh of ours to take the surface from")
    job("CGAL Mesh_3", [DEBIAN_PYTHON, me, "--worker", "cgal", vol, os.path.join(d, "cgal"),
                        "-" if alpha is None else repr(alpha), "-" if beta is None else repr(beta)],
        os.path.join(d, "cgal"), ".node")
    if "ctd" in ok:
        write_medit(os.path.join(d, "ctd.mesh"), *q.read_msh_tets(ok["ctd"]))
        job("MMG3D -optim", [mmg_binary(), *MMG_ARGS, "-in", os.path.join(d, "ctd.mesh"),
                             "-out", os.path.join(d, "mmg.mesh")], os.path.join(d, "mmg"), ".mesh")
    else:
        job("MMG3D -optim", [], None, None, pending="no plain ctd mesh to optimise")
    print(f"[compare] {dom['name']}: ours done ({', '.join(r['status'] for r in dom['rows'][:2])})", flush=True)
    return dom


def run_peer(args, job, t_start):
    """One peer child process; fills its row (status, wall = the tool's own seconds)."""
    row, cmd, prefix, d, limit, ext = job
    if time.perf_counter() - t_start > args.budget:
        row.update(status="skipped", wall=0.0, detail=f"run budget of {args.budget:g} s spent")
        return
    for old in (prefix + ".seconds", prefix + ext):
        if os.path.exists(old):
            os.remove(old)
    row.update(q.run_child(cmd, prefix, limit, cwd=d))
    row["limit"] = limit
    if row["status"] in ("failed", "crash"):
        row["detail"] = last_error(prefix) or row["detail"]
    if row["status"] == "ok":
        if os.path.exists(prefix + ".seconds"):     # the library call's own time (workers)
            with open(prefix + ".seconds") as fs:
                row["process_wall"], row["wall"] = row["wall"], float(fs.read())
        row["mesh"] = prefix + ext
    print(f"[compare] {os.path.basename(d)}: {row['tool']} {row['status']} {row['wall']:.1f} s", flush=True)


def last_error(prefix):
    """The last meaningful line a failed child wrote (a Python exception's message, TetGen's
    or MMG's last words)."""
    for ext in (".stderr", ".stdout"):
        try:
            with open(prefix + ext, errors="replace") as f:
                lines = [l.strip() for l in f.read()[-20000:].splitlines() if l.strip()]
        except OSError:
            continue
        lines = [l for l in lines if not l.startswith(("File ", "^", "~"))]
        if lines:
            return lines[-1][:200]
    return None


def finish(args, dom):
    """Runs our checker on every mesh of the domain (compare_peers.inspect)."""
    meshes = dom.pop("meshes") + [(row, row["mesh"]) for row, *_ in dom.pop("jobs") if row.get("status") == "ok"]
    t0 = time.perf_counter()
    dom["reference_betti"] = None
    if meshes:
        dom["reference_betti"] = cp.inspect(args, os.path.dirname(dom["vol"]), dom["vol"], dom["bounds"], meshes)
    dom["inspect_seconds"] = time.perf_counter() - t0
    for r in dom["rows"]:
        r.pop("mesh", None)
    del dom["build"]
    print(f"[compare] {dom['name']}: checked ({dom['inspect_seconds']:.0f} s)", flush=True)
    return dom


# ----------------------------------------------------------------------------
# derived numbers
# ----------------------------------------------------------------------------

def level_distance(r):
    """Largest distance (voxels) of a boundary sample to its level set: the checker's
    max_distance, or max_beyond when some points lie beyond the 0.5-voxel bound."""
    lv = r.get("level")
    if not lv:
        return None
    return lv["max_beyond"] if lv.get("beyond") else lv["max_distance"]


def betti_error(r, ref):
    """Sum over i of |b_i - reference b_i|; None when not inspected or not a closed manifold."""
    if r.get("betti") is None or ref is None:
        return None
    return int(sum(abs(a - b) for a, b in zip(r["betti"], ref)))


def fmt(x, spec, dash="–"):
    return dash if x is None else format(x, spec)


def fmt_dist(x):
    if x is None:
        return "–"
    return "> 2 (none found)" if x == float("inf") else f"{x:.3f}"


# ----------------------------------------------------------------------------
# plots (matplotlib, Agg; small PNGs)
# ----------------------------------------------------------------------------

def savefig(fig, folder, name):
    import matplotlib.pyplot as plt
    fig.savefig(os.path.join(folder, name), dpi=90)
    plt.close(fig)
    return name


def plot_dihedral(folder, dom):
    """Dihedral histograms of one domain, one panel per tool, side by side."""
    import matplotlib.pyplot as plt
    rows = [r for r in dom["rows"] if r.get("histogram")]
    if not rows:
        return None
    fig, axes = plt.subplots(1, len(rows), figsize=(2.1 * len(rows), 2.0), sharey=False, squeeze=False)
    for ax, r in zip(axes[0], rows):
        h = np.asarray(r["histogram"], dtype=float)
        ax.bar(np.arange(len(h)) + 0.5, 100.0 * h / max(h.sum(), 1.0), width=1.0, color=COLORS.get(r["tool"]))
        ax.set_xlim(0, 180)
        ax.set_xticks([0, 60, 120, 180])
        ax.set_title(f"{r['tool']}\nmin {r['min']:.1f}°, max {r['max']:.1f}°", fontsize=7)
        ax.tick_params(labelsize=7)
        ax.set_xlabel("dihedral (°)", fontsize=7)
    axes[0][0].set_ylabel("% of angles", fontsize=7)
    fig.suptitle(dom["name"], fontsize=8)
    fig.tight_layout()
    return savefig(fig, folder, f"dihedral_{dom['name']}.png")


def grouped_bars(ax, doms, value, log=False, hline=None):
    """One group of bars per domain, one bar per tool; a missing value (no mesh: see the
    table) is an 'x' just below the smallest bar."""
    width = 0.8 / len(TOOLS)
    cells = []                      # (x, tool, value or None)
    for k, tool in enumerate(TOOLS):
        for i, dom in enumerate(doms):
            r = next((r for r in dom["rows"] if r["tool"] == tool), None)
            cells.append((i - 0.4 + (k + 0.5) * width, tool, value(r, dom) if r else None))
    vals = [v for _, _, v in cells if v is not None and (v > 0 or not log)]
    floor = (min(vals) / 2.0 if vals else 1.0) if log else 0.0
    for tool in TOOLS:
        have = [(x, v) for x, t, v in cells if t == tool and v is not None]
        miss = [x for x, t, v in cells if t == tool and v is None]
        ax.bar([x for x, _ in have], [v for _, v in have], width=width, color=COLORS[tool], label=tool)
        ax.plot(miss, [floor] * len(miss), "x", color=COLORS[tool], ms=4)
    ax.set_xticks(range(len(doms)))
    ax.set_xticklabels([d["name"] for d in doms], rotation=30, ha="right", fontsize=7)
    ax.tick_params(axis="y", labelsize=7)
    if log:
        ax.set_yscale("log")
        ax.set_ylim(bottom=floor / 1.5)
    if hline is not None:
        ax.axhline(hline, color="k", lw=0.6, ls="--")


def plot_counts_times(folder, doms):
    import matplotlib.pyplot as plt
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(9, 5.2))
    grouped_bars(a1, doms, lambda r, d: r.get("tets") if r.get("status") == "ok" else None, log=True)
    a1.set_ylabel("tets", fontsize=7)
    a1.legend(fontsize=7, ncol=6, loc="lower left", bbox_to_anchor=(0.0, 1.0), frameon=False)
    grouped_bars(a2, doms, lambda r, d: r.get("wall") if r.get("status") == "ok" else None, log=True)
    a2.set_ylabel("time (s; x = no mesh)", fontsize=7)
    fig.tight_layout()
    return savefig(fig, folder, "tets_time.png")


def plot_betti(folder, doms):
    """Heat map: sum |b_i - reference| per domain and tool; grey = no Betti numbers."""
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 0.32 * len(doms) + 1.2))
    m = np.full((len(doms), len(TOOLS)), np.nan)
    for i, dom in enumerate(doms):
        for j, tool in enumerate(TOOLS):
            r = next((r for r in dom["rows"] if r["tool"] == tool), None)
            e = betti_error(r, dom.get("reference_betti")) if r else None
            txt = "–" if r is None else (str(e) if e is not None else
                                          {"ok": "n/m"}.get(r.get("status"), r.get("status", "?")[:7]))
            if e is not None:
                m[i, j] = e
            ax.text(j, i, txt, ha="center", va="center", fontsize=7)
    cmap = plt.get_cmap("Reds").copy()
    cmap.set_bad("#dddddd")
    ax.imshow(np.ma.masked_invalid(np.log1p(m)), cmap=cmap, vmin=0, vmax=np.log1p(50), aspect="auto")
    ax.set_xticks(range(len(TOOLS)))
    ax.set_xticklabels(TOOLS, fontsize=7, rotation=20, ha="right")
    ax.set_yticks(range(len(doms)))
    ax.set_yticklabels([d["name"] for d in doms], fontsize=7)
    ax.set_title("Betti-number error: sum |b_i - b_i(trilinear)|  (grey: no Betti numbers; n/m: "
                 "boundary not a closed manifold)", fontsize=7)
    fig.tight_layout()
    return savefig(fig, folder, "betti_errors.png")


def plot_level(folder, doms):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9, 2.8))
    grouped_bars(ax, doms, lambda r, d: (min(level_distance(r), 2.5) if level_distance(r) is not None else None),
                 hline=0.5)
    ax.set_ylabel("max boundary distance\nto the level set (voxels)", fontsize=7)
    ax.set_ylim(0, 2.6)
    ax.legend(fontsize=7, ncol=6, loc="lower left", bbox_to_anchor=(0.0, 1.0), frameon=False)
    fig.tight_layout()
    return savefig(fig, folder, "level_distance.png")


# ----------------------------------------------------------------------------
# the report
# ----------------------------------------------------------------------------

def machine_info(args):
    def sh(cmd):
        try:
            return subprocess.run(cmd, capture_output=True, text=True, timeout=30).stdout.strip()
        except (OSError, subprocess.TimeoutExpired):
            return "?"
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    mem = next((l.split(":", 1)[1].strip() for l in open("/proc/meminfo") if l.startswith("MemTotal")), "?")

    from importlib import metadata

    def version(dist):
        try:
            return metadata.version(dist)
        except metadata.PackageNotFoundError:
            return None
    return {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "nproc": os.cpu_count(), "cpu": cpu, "mem_total": mem, "uname": platform.platform(),
            "python": platform.python_version(), "git_head": sh(["git", "-C", REPO, "rev-parse", "--short", "HEAD"]),
            "tptd_mesh": sh([args.bin, "--version"]), "tetgen": version("tetgen"), "pytetwild": version("pytetwild"),
            "mmgpy": version("mmgpy"),
            "pygalmesh": sh([DEBIAN_PYTHON, "-c", "import pygalmesh; print(pygalmesh.__version__)"]),
            "python3_pygalmesh": sh(["dpkg-query", "-W", "-f=${Version}", "python3-pygalmesh"]) or None}


def table(dom):
    ref = dom.get("reference_betti")
    lines = ["| tool | status | tets | time (s) | min ° | max ° | valid | Betti (ref " +
             ("–" if ref is None else ",".join(map(str, ref))) + ") | max level dist. (vox) | problems |",
             "|---|---|---:|---:|---:|---:|---|---|---:|---|"]
    # n/m: the boundary is not a closed manifold, so the checker gives no Betti numbers
    for r in dom["rows"]:
        st = r.get("status", "?")
        if st not in ("ok",):
            st = f"**{st}**" + (f" ({r['detail'][:80]})" if r.get("detail") else "")
        betti = ("n/m" if r.get("valid") is not None else "–") if r.get("betti") is None else \
            ",".join(map(str, r["betti"]))
        if r.get("matches_reference") is True:
            betti += " ✓"
        elif r.get("matches_reference") is False:
            betti += " ✗"
        probs = "; ".join(r.get("problems") or []) or ("–" if r.get("valid") is None else "none")
        lines.append(f"| {r['tool']} | {st} | {fmt(r.get('tets'), ',d')} | "
                     f"{fmt(r.get('wall') if r.get('status') == 'ok' else None, '.2f')} | "
                     f"{fmt(r.get('min'), '.2f')} | {fmt(r.get('max'), '.2f')} | "
                     f"{'–' if r.get('valid') is None else ('yes' if r['valid'] else '**no**')} | {betti} | "
                     f"{fmt_dist(level_distance(r))} | {md(probs)[:160]} |")
    return "\n".join(lines)


def md(s):
    return s.replace("|", "\\|").replace("\n", " ")


def per_tool_summary(doms):
    """Per tool: runs, meshes made, meshes valid with the reference Betti numbers, Betti
    numbers wrong, none (boundary not a closed manifold), invalid, boundary beyond 0.5 voxel,
    the range of the per-domain smallest angle, and the domains without a mesh by status."""
    out = []
    for tool in TOOLS:
        rows = [(d, r) for d in doms for r in d["rows"] if r["tool"] == tool]
        ok = [(d, r) for d, r in rows if r.get("status") == "ok" and r.get("tets") is not None]
        mins = [r["min"] for _, r in ok if r.get("min") is not None]
        bad = {}
        for d, r in rows:
            if r.get("status") != "ok":
                bad.setdefault(r.get("status", "?"), []).append(d["name"])
        out.append({"tool": tool, "runs": len(rows), "meshes": len(ok),
                    "good": [d["name"] for d, r in ok if r.get("valid") and r.get("matches_reference")],
                    "betti_wrong": [d["name"] for d, r in ok if r.get("betti") is not None
                                    and r.get("matches_reference") is False],
                    "no_betti": [d["name"] for d, r in ok if r.get("betti") is None],
                    "invalid": [d["name"] for d, r in ok if r.get("valid") is False],
                    "level_over_half": [d["name"] for d, r in ok if (level_distance(r) or 0) > 0.5],
                    "min_lo": min(mins) if mins else None, "min_hi": max(mins) if mins else None,
                    "not_ok": bad})
    return out


def summary_table(summary):
    def names(v):
        return f"{len(v)}" + (f" ({', '.join(v)})" if v else "")
    lines = ["| tool | meshes / runs | valid, reference Betti | Betti wrong | no Betti (n/m) | invalid | "
             "beyond 0.5 vox | smallest angle per domain | no mesh |",
             "|---|---|---|---|---|---|---|---|---|"]
    for s in summary:
        rng = "–" if s["min_lo"] is None else f"{s['min_lo']:.1f}°–{s['min_hi']:.1f}°"
        nots = "; ".join(f"{k}: {', '.join(v)}" for k, v in s["not_ok"].items()) or "–"
        lines.append(f"| {s['tool']} | {s['meshes']} / {s['runs']} | {len(s['good'])} | {names(s['betti_wrong'])} | "
                     f"{names(s['no_betti'])} | {names(s['invalid'])} | {names(s['level_over_half'])} | {rng} | "
                     f"{nots} |")
    return lines


def comparisons(doms):
    """Per peer against ctd --quality on the domains where both made a mesh: where the peer
    has the larger smallest angle, fewer tets, the right topology where ours is wrong (and
    the reverse), and its time as a multiple of ours (same run, same machine)."""
    lines = []
    for tool in TOOLS[2:]:
        angle, fewer, topo_ours, topo_theirs, ratios, both = [], [], [], [], [], 0
        for d in doms:
            ours = next((r for r in d["rows"] if r["tool"] == "ctd --quality"), {})
            r = next((r for r in d["rows"] if r["tool"] == tool), {})
            if ours.get("tets") is None or r.get("tets") is None:
                continue
            both += 1
            if r["min"] > ours["min"]:
                angle.append(f"{d['name']} ({r['min']:.1f}° vs {ours['min']:.1f}°)")
            if r["tets"] < ours["tets"]:
                fewer.append(f"{d['name']} ({r['tets']:,} vs {ours['tets']:,})")
            good = lambda x: x.get("matches_reference") is True and x.get("valid") is True  # noqa: E731
            if good(ours) and not good(r):
                topo_ours.append(d["name"])
            if good(r) and not good(ours):
                topo_theirs.append(d["name"])
            if ours.get("wall") and r.get("wall"):
                ratios.append(r["wall"] / ours["wall"])
        if not both:
            lines.append(f"- **{tool}**: no domain where both it and ctd --quality made a mesh.")
            continue
        rt = (f"time {np.median(ratios):.1f}× ours (median; {min(ratios):.1f}×–{max(ratios):.1f}×)"
              if ratios else "no times")
        lines.append(f"- **{tool}** ({both} domains): larger smallest angle on {len(angle)} "
                     f"({', '.join(angle) or '–'}); fewer tets on {len(fewer)} ({', '.join(fewer) or '–'}); "
                     f"valid with the reference Betti numbers where ours is not: {', '.join(topo_theirs) or 'none'}; "
                     f"ours valid with the reference Betti numbers where it is not: {', '.join(topo_ours) or 'none'}; "
                     f"{rt}.")
    return lines


def render(payload, plots):
    doms = payload["domains"]
    m = payload["machine"]
    st = payload["settings"]
    L = ["# Peer comparison: tptd-mesh against TetGen, fTetWild, CGAL Mesh_3 and MMG3D", "",
         f"Generated by `{payload['command']}` in {payload['total_seconds'] / 60:.1f} min "
         f"({m['date']}, {m['tptd_mesh']}, commit {m['git_head']}). Do not edit by hand: "
         "rerun the command.", "",
         "## Setup", "",
         f"- Machine: {m['nproc']}-core {m['cpu']} VM, {m['mem_total']} RAM, {m['uname']}. "
         f"Load average at start {payload['loadavg_start'][0]:.2f}, at the end {payload['loadavg_end'][0]:.2f} "
         f"(this run used {st['jobs']} runs at a time; other work shared the machine"
         f"{'' if payload['loadavg_start'][0] > 1.5 or payload['loadavg_end'][0] > 2.5 else ' at times'}). "
         "Compare times only as ratios within this run.",
         f"- Versions: tetgen (PyPI) {m['tetgen']}, pytetwild {m['pytetwild']}, mmgpy {m['mmgpy']} (mmg3d_O3), "
         f"pygalmesh {m['pygalmesh']} (Debian 12 python3-pygalmesh {m['python3_pygalmesh']}, built with CGAL 5.5 headers), Python {m['python']}.",
         f"- Sizes: the analytic domains at {st['size']}³ and the MNI crops at {st['mni_crop']}³ (the test "
         "tests/py/compare_peers.py uses 20³–24³); the whole MNI volumes at 197×233×189. "
         f"Per-run limits: ours {st['ours_timeout']:g} s, peers {st['peer_timeout']:g} s on the grids and "
         f"crops, {st['full_peer_timeout']:g} s on the whole volumes; runs that would start after "
         f"{st['budget']:g} s are `skipped`. The sizes and limits are chosen to keep the whole run near half an "
         f"hour on this machine; this run took {payload['total_seconds'] / 60:.0f} min (see the tables for what "
         "finished within the limits).",
         "- Tools: `ctd` and `ctd --quality` (`tptd-mesh VOL [--alpha A] [--beta B] -o M.msh --msh-version "
         "4.1-binary -j 1 [--quality]`: one thread, like every peer here); "
         f"TetGen `-{TETGEN_SWITCHES}` and fTetWild (`edge_length_abs={cp.FTETWILD_EDGE:g}`, "
         f"`epsilon={cp.FTETWILD_EPSILON:g}`, optimize) on the boundary surface of our `ctd --quality` "
         "mesh (with a hole point per cavity), so their topology starts from ours; CGAL Mesh_3 "
         "(pygalmesh `generate_from_array`) on the uint8 label image \"voxel value in the interval\" "
         f"with {', '.join(f'{k}={v}' for k, v in CGAL.items())} — CGAL meshes a labelled image, "
         "so it never sees the level set between voxels; MMG3D `mmg3d_O3 " + " ".join(MMG_ARGS) +
         "` on our plain `ctd` mesh (medit .mesh).",
         "- Times: ours = the whole process (reading the volume, writing the mesh); TetGen, fTetWild and "
         "CGAL = the library call only (the surface extraction for TetGen/fTetWild is not counted); "
         "MMG3D = the mmg3d_O3 process. Timeouts are wall-clock limits on the child process.",
         "- Judge: every mesh goes through our checker, `tptd-mesh --inspect MESH --volume VOL --alpha A "
         "[--beta B] --json J`: validity (conformity, orientation, manifold boundary), problems, Betti "
         "numbers against those of the trilinear interval, dihedral angles, and the distance of the "
         "boundary to the level sets (peer meshes carry no boundary labels: each boundary triangle is "
         "labelled by its nearest level). The checker's bound is 0.5 voxel; a distance above it is a "
         "problem (`off_level`), and a point with no level found within 2 voxels shows as \"> 2\".",
         "", "## Summary", ""]
    L += summary_table(payload["summary"])
    L += ["", "Peers against `ctd --quality`, domain by domain (both meshes made):", ""] + comparisons(doms)
    L += ["", *payload["notes"], "", "## Plots", ""]
    for title, p in (("Element count and time per tool (log scales)", plots.get("tets_time")),
                     ("Betti-number errors", plots.get("betti")),
                     ("Boundary distance to the level set (dashed: the checker's 0.5-voxel bound)",
                      plots.get("level"))):
        if p:
            L += [f"{title}:", "", f"![{title}]({p})", ""]
    L += ["## Domains", ""]
    for dom in doms:
        bounds = (f"alpha = {dom['alpha']!r}" if dom["alpha"] is not None else "") + \
                 (", " if dom["alpha"] is not None and dom["beta"] is not None else "") + \
                 (f"beta = {dom['beta']!r}" if dom["beta"] is not None else "")
        L += [f"### {dom['name']}", "",
              f"{dom['note']}; grid {'×'.join(map(str, dom['shape']))} ({dom['dtype']}), {bounds}; "
              f"trilinear reference Betti numbers "
              f"{'–' if dom.get('reference_betti') is None else tuple(dom['reference_betti'])}."
              + (f" Peer surface: boundary of {dom['surface']['from']}, {dom['surface']['triangles']:,} "
                 f"triangles, {dom['surface']['holes']} hole point(s)." if dom.get("surface") else ""), "",
              table(dom), ""]
        if plots.get(dom["name"]):
            L += [f"![dihedral angles, {dom['name']}]({plots[dom['name']]})", ""]
    return "\n".join(L) + "\n"


def notes(doms):
    """Fixed caveats, each stated only when this run measured it."""
    out = ["Notes:", ""]
    far = [d["name"] for d in doms for r in d["rows"] if r["tool"] == "ctd" and (level_distance(r) or 0) > 0.5]
    if far:
        out.append(f"- Known limit, measured here: plain `ctd` puts boundary points more than 0.5 voxel off "
                   f"the level set on {', '.join(far)} (fields rough at the voxel scale: a face or inner diagonal with both ends on one side of a level and a crossing between). "
                   "The checker flags these meshes `off_level`.")
        q_far = [d["name"] for d in doms for r in d["rows"] if r["tool"] == "ctd --quality"
                 and (level_distance(r) or 0) > 0.5]
        out.append("- `ctd --quality` keeps such points off the level set too, on "
                   f"{', '.join(q_far) or 'none of these'} (the pass keeps the boundary where plain ctd put it).")
    else:
        out.append("- Plain `ctd` stayed within 0.5 voxel of the level sets on every domain of this run.")
    broken = [(d["name"], r) for d in doms for r in d["rows"] if r["tool"].startswith("ctd")
              and any(not p.startswith("off_level") for p in r.get("problems") or [])]
    for name, r in broken:
        out.append(f"- **Defect of ours, measured here:** `{r['tool']}` on {name} wrote a mesh the checker "
                   f"rejects for more than the level distance: {'; '.join(r['problems'])}. The runs here have "
                   "no `--check` (the checker judges every mesh afterwards), so it was written. Command: "
                   f"`{r['command'].replace(REPO + '/', '')}`.")
    warned = [(d["name"], r) for d in doms for r in d["rows"] if r["tool"] == "ctd"
              and any("critical value" in w or "saddle" in w for w in r.get("warnings") or [])]
    for name, r in warned:
        w = next((w for w in r["warnings"] if "critical value" in w), None) or \
            next(w for w in r["warnings"] if "saddle" in w)
        out.append(f"- tptd-mesh warned on {name} that the bound is near critical values: \"{w}\"")
    slow = [(d["name"], r) for d in doms for r in d["rows"] if r["tool"].startswith("ctd") and r.get("status") != "ok"]
    for name, r in slow:
        out.append(f"- `{r['tool']}` made no mesh on {name}: {r.get('status')} ({r.get('detail') or ''}). "
                   "It ran on one thread on a shared machine; the `--quality` pass has no time limit unless "
                   "`--quality-time` is given. TetGen and fTetWild then mesh the boundary of the plain `ctd` "
                   "mesh there.")
    cg_out = [d["name"] for d in doms for r in d["rows"] if r["tool"] == "CGAL Mesh_3"
              and any(p.startswith("outside_grid") for p in r.get("problems") or [])]
    if cg_out:
        out.append(f"- CGAL closes the domain where it meets the image border about half a voxel outside the "
                   f"grid box (it pads the label image with label 0), so the checker reports `outside_grid` "
                   f"on {', '.join(cg_out)}; ours ends at the grid box. Its level distance is then not "
                   "measured (–).")
    nm = sorted({d["name"] for d in doms for r in d["rows"] if r.get("valid") is False and r.get("betti") is None})
    if nm:
        out.append(f"- `n/m` in the Betti column: the boundary is not a closed manifold (non-manifold edges or "
                   f"vertices), so the mesh has no Betti numbers to compare; measured on {', '.join(nm)}.")
    out += ["- TetGen and fTetWild mesh our own boundary surface, so their Betti numbers mostly inherit "
            "ours; a marching-cubes surface instead (tests/py/compare_peers.py runs both) changes the "
            "topology on the near-touching and thin domains.",
            "- CGAL sees only the voxel labels: features thinner than a voxel (the 0.3-voxel gap, the "
            "thin shell) are resolved by the label image, not by the trilinear interpolant, and its "
            "boundary lies up to about half a voxel or more from the level set by construction.",
            "- MMG3D with `-noinsert` only moves and swaps; `-hausd 0.01` lets it move boundary points, "
            "so its level distance and topology are measured, not assumed.",
            "- fTetWild's result changes from run to run (one run is reported)."]
    return out


# ----------------------------------------------------------------------------

def parse_args():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=None, help="tptd-mesh (default: $CARGO_TARGET_DIR or target/release)")
    ap.add_argument("--size", type=int, default=48, help="grid of the analytic domains (default 48)")
    ap.add_argument("--mni-crop", type=int, default=48, help="MNI crops (default 48)")
    ap.add_argument("--no-full", action="store_true", help="leave out the whole MNI volumes")
    ap.add_argument("--domains", default=None, help="comma-separated subset of the domain names")
    ap.add_argument("--peer-timeout", type=float, default=120.0, help="per peer run on grids and crops (s)")
    ap.add_argument("--full-peer-timeout", type=float, default=60.0, help="per peer run on whole volumes (s)")
    ap.add_argument("--ours-timeout", type=float, default=600.0, help="per tptd-mesh run (s)")
    ap.add_argument("--budget", type=float, default=1800.0,
                    help="peer runs that would start later than this (s from the start) are skipped")
    ap.add_argument("--jobs", type=int, default=2, help="runs at a time (default 2)")
    ap.add_argument("--report-dir", default=None, help="report folder (default benchmarks/report)")
    ap.add_argument("--work", default=OUT, help="volumes, meshes, logs (default benchmarks/out/compare)")
    ap.add_argument("--quick", action="store_true", help="smoke run: 24^3, torus + two_spheres, no full MNI, "
                    "report to benchmarks/out/compare_quick/report")
    ap.add_argument("--render-only", action="store_true",
                    help="rewrite report.md and the plots from --work's results.json, without running")
    ap.add_argument("--worker", nargs="+", help=argparse.SUPPRESS)
    return ap.parse_args()


def default_bin():
    target = os.environ.get("CARGO_TARGET_DIR", os.path.join(REPO, "target"))
    return os.path.join(target, "release", "tptd-mesh")


def main():
    args = parse_args()
    if args.worker:
        kind, *rest = args.worker
        return {"cgal": cgal_worker}[kind](*rest)
    if args.render_only:
        with open(os.path.join(args.work, "results.json")) as fj:
            return write_report(json.load(fj), args.report_dir or REPORT)
    command = "python3 benchmarks/compare.py" + "".join(f" {a}" for a in sys.argv[1:])
    if args.quick:
        args.size, args.mni_crop, args.no_full = 24, 24, True
        args.domains = args.domains or "torus,two_spheres"
        args.work = os.path.join(HERE, "out", "compare_quick")
        args.report_dir = args.report_dir or os.path.join(args.work, "report")
    args.bin = os.path.abspath(args.bin or default_bin())
    args.report_dir = args.report_dir or REPORT
    os.makedirs(args.report_dir, exist_ok=True)
    os.makedirs(args.work, exist_ok=True)
    machine = machine_info(args)
    load0 = os.getloadavg()
    t0 = time.perf_counter()
    doms = [{"name": n, "build": b, "full": full} for n, b, full in domains(args)]
    with ThreadPoolExecutor(args.jobs) as pool:
        # the whole volumes first: their --quality runs are the longest, the grids fill the other slot
        first = sorted(range(len(doms)), key=lambda i: not doms[i]["full"])
        done = dict(zip(first, pool.map(lambda i: run_ours(args, doms[i]), first)))
        doms = [done[i] for i in range(len(doms))]
        print(f"[compare] ours on {len(doms)} domains: {time.perf_counter() - t0:.0f} s", flush=True)
        jobs = [j for d in doms if not d["full"] for j in d["jobs"]] + \
               [j for d in doms if d["full"] for j in d["jobs"]]
        list(pool.map(lambda j: run_peer(args, j, t0), jobs))
        print(f"[compare] {len(jobs)} peer runs: {time.perf_counter() - t0:.0f} s", flush=True)
        doms = list(pool.map(lambda d: finish(args, d), doms))
    for d in doms:
        d["vol"] = os.path.relpath(d["vol"], REPO)
    payload = {"command": command, "machine": machine, "loadavg_start": load0, "loadavg_end": os.getloadavg(),
               "total_seconds": time.perf_counter() - t0, "domains": doms,
               "settings": {"size": args.size, "mni_crop": args.mni_crop, "peer_timeout": args.peer_timeout,
                            "full_peer_timeout": args.full_peer_timeout, "ours_timeout": args.ours_timeout,
                            "budget": args.budget, "jobs": args.jobs, "cgal": CGAL, "mmg": MMG_ARGS,
                            "tetgen": TETGEN_SWITCHES, "ftetwild_edge": cp.FTETWILD_EDGE,
                            "ftetwild_epsilon": cp.FTETWILD_EPSILON}}
    with open(os.path.join(args.work, "results.json"), "w") as fj:
        json.dump(payload, fj, indent=1, default=str)
    write_report(payload, args.report_dir)


def write_report(payload, rd):
    """report.md and the plots from the measured payload (also --render-only)."""
    import matplotlib
    matplotlib.use("Agg")
    doms = payload["domains"]
    payload["summary"] = per_tool_summary(doms)
    payload["notes"] = notes(doms)
    os.makedirs(rd, exist_ok=True)
    plots = {d["name"]: plot_dihedral(rd, d) for d in doms}
    plots.update(tets_time=plot_counts_times(rd, doms), betti=plot_betti(rd, doms), level=plot_level(rd, doms))
    with open(os.path.join(rd, "report.md"), "w") as fm:
        fm.write(render(payload, plots))
    print(f"[compare] wrote {rd}/report.md (run of {payload['total_seconds']:.0f} s)")


if __name__ == "__main__":
    sys.exit(main())
