#!/usr/bin/env python3
"""Element-quality benchmark: tptd-mesh (ctd, and ctd --quality once that flag
exists) against TetGen and fTetWild on the same domains.  See the "Element
quality" section of benchmarks/README.md.

  python3 benchmarks/quality.py                  # all domains, N = 32, MNI crops 40^3, 60 s timeouts
  python3 benchmarks/quality.py --size 48 --mri-crop 64 --timeout 300 --ftetwild-timeout 300   # the issue's sizes
  python3 benchmarks/quality.py --quick          # N = 32, sphere + torus, short timeouts (< 2 min)
  python3 benchmarks/quality.py --domains sphere,shell --no-ftetwild --timeout 120
  python3 benchmarks/quality.py --domains sphere,torus,genus3,shell,two_spheres --no-tetgen \
      --targets 20/150,25/145,30/140,35/135 --ftetwild-runs 5 \
      --out benchmarks/quality_targets_results   # higher targets

For every domain and interval:

  1. ours      `tptd-mesh IN [--alpha A] [--beta B] -o OUT.msh --report R.json`, and
               the same with `--quality` when `tptd-mesh --help` lists it; each a fresh,
               timed process.  The .msh is read with meshio.
  2. surface   the boundary of our mesh (triangles used by exactly one tet, outward),
               written as a TetGen .smesh with one hole point per enclosed cavity.
  3. TetGen    `tetgen -pq1.2F surf.smesh` and `tetgen -pq1.2/10F surf.smesh`, fresh
               timed processes with --timeout and an address-space limit; aborts and
               timeouts are recorded, never raised.
  4. fTetWild  `pytetwild.tetrahedralize(V, F, edge_length_abs=..., optimize=True,
               vtk_ordering=True)` in a child process (this script with
               --ftetwild-worker) with --ftetwild-timeout.  Its result changes from run
               to run: with --ftetwild-runs N the row is the run of median smallest
               angle (one that did not finish counts lowest), every run noted.

Statistics (numpy, vectorised, in chunks): all six dihedral angles of every tet; min,
max, percentiles, % of tets whose smallest angle is below 5/10/15 deg, % whose largest
is above 155/165 deg, tet count, time.

Writes benchmarks/quality_results.{md,json} and benchmarks/quality_hist.png (dihedral
histogram of ours before / after --quality); --quick writes the *_quick variants, which
are git-ignored.  Volumes go to benchmarks/data/quality/, meshes and logs to
benchmarks/out/quality/ (both git-ignored).
"""
import argparse
import datetime
import json
import math
import os
import platform
import resource
import shutil
import signal
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
DATA = os.path.join(HERE, "data", "quality")
OUT = os.path.join(HERE, "out", "quality")
SEED = 20240611

T1_NAME = "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz"
WM_NAME = "mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz"

ALL_DOMAINS = ["sphere", "torus", "genus3", "shell", "two_spheres", "random", "mni_wm", "mni_t1"]
QUICK_DOMAINS = ["sphere", "torus"]

HIST_BIN = 0.1                      # degrees; fine histogram used for percentiles
PCTS = (1, 5, 50, 95, 99)
MIN_BELOW = (5, 10, 15)             # % of tets whose smallest dihedral is below
MAX_ABOVE = (155, 165)              # % of tets whose largest dihedral is above
CHUNK = 1 << 20                     # tets per numpy chunk

# Defaults sized so that the full run takes ~15-20 min on 2 shared cores.  The issue's
# "N = 48, MNI 64^3, 300 s per peer run" (--size 48 --mri-crop 64 --timeout 300
# --ftetwild-timeout 300) takes well over an hour there: at N = 32 TetGen -pq1.2 alone
# already needs 20-50 s per domain and multiplies the tets 20-25x.
TIMEOUT = 60.0
QUICK_TIMEOUT = 15.0


# ----------------------------------------------------------------------------
# domains: float32 .npy, array index [i, j, k] = grid point (x, y, z), unit spacing
# ----------------------------------------------------------------------------

def grid(n):
    """Broadcastable coordinates x, y, z (voxel units) of an n^3 grid, centre c = n // 2
    (a grid point, so the two-spheres gap straddles a grid plane)."""
    i = np.arange(n, dtype=np.float64) - n // 2
    return i[:, None, None], i[None, :, None], i[None, None, :]


def sdf_sphere(x, y, z, r, cx=0.0, cy=0.0, cz=0.0):
    return np.sqrt((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) - r


def sdf_torus_z(x, y, z, big, small, cx=0.0):
    """Torus around an axis parallel to z through (cx, 0)."""
    q = np.sqrt((x - cx) ** 2 + y ** 2) - big
    return np.sqrt(q ** 2 + z ** 2) - small


def smooth_min(a, b, k):
    """Polynomial smooth minimum (Quilez), blend width k."""
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return b + (a - b) * h - k * h * (1.0 - h)


def dom_sphere(n):
    x, y, z = grid(n)
    return sdf_sphere(x, y, z, 0.35 * n), [(None, 0.0)], "ball, radius 0.35 N"


def dom_torus(n):
    x, y, z = grid(n)
    return sdf_torus_z(x, y, z, 0.28 * n, 0.11 * n), [(None, 0.0)], "solid torus, R = 0.28 N, r = 0.11 N"


def dom_genus3(n):
    """Three coplanar solid tori in a row, tangent rings, smooth union -> genus 3."""
    x, y, z = grid(n)
    big, small = 0.12 * n, 0.06 * n
    d = sdf_torus_z(x, y, z, big, small, -2 * big)
    for cx in (0.0, 2 * big):
        d = smooth_min(d, sdf_torus_z(x, y, z, big, small, cx), 0.04 * n)
    return d, [(None, 0.0)], "smooth union (k = 0.04 N) of 3 tori R = 0.12 N, r = 0.06 N, tangent rings (genus 3)"


def dom_shell(n, t=0.6):
    x, y, z = grid(n)
    return (sdf_sphere(x, y, z, 0.35 * n), [(-t, t)],
            f"thin spherical shell: sphere SDF, radius 0.35 N, two-sided band [-{t}, {t}] (~{2 * t:g} voxel thick)")


def dom_two_spheres(n, gap=0.3):
    """Two balls whose surfaces are `gap` voxels apart, the gap centred on grid plane x = 0."""
    x, y, z = grid(n)
    r = 0.22 * n
    off = r + 0.5 * gap
    d = np.minimum(sdf_sphere(x, y, z, r, -off), sdf_sphere(x, y, z, r, off))
    return d, [(None, 0.0)], f"two balls, radius 0.22 N, {gap} voxel apart (min of the two SDFs)"


def dom_random(n):
    """Seeded band-limited Gaussian field (unit std, correlation N/12 voxels), plus a ramp
    outside radius 0.38 N so {f <= 0} stays inside the grid."""
    sys.path.insert(0, HERE)
    from make_data import band_limited_noise
    rng = np.random.default_rng(SEED + n)
    g = band_limited_noise(n, n / 12.0, rng).astype(np.float64)
    x, y, z = grid(n)
    r = np.sqrt(x ** 2 + y ** 2 + z ** 2)
    return (g + np.maximum(0.0, r - 0.38 * n), [(None, 0.0)],
            f"random smooth field: unit-std Gaussian noise, correlation {n / 12.0:g} voxel, seed {SEED + n}, "
            "+ max(0, r - 0.38 N)")


def nilearn_data_dir():
    sys.path.insert(0, HERE)
    from make_data import nilearn_data_dir as find
    return find()


def mri_crop(fname, crop):
    """Central crop^3 of an MNI template from the installed nilearn package."""
    nd = nilearn_data_dir()
    if nd is None or not os.path.exists(os.path.join(nd, fname)):
        raise FileNotFoundError(f"{fname} not found (pip install nilearn nibabel)")
    import nibabel as nib
    a = np.asarray(nib.load(os.path.join(nd, fname)).dataobj)
    lo = [max(0, s // 2 - crop // 2) for s in a.shape]
    return a[lo[0]:lo[0] + crop, lo[1]:lo[1] + crop, lo[2]:lo[2] + crop], lo


def dom_mni_wm(crop):
    a, lo = mri_crop(WM_NAME, crop)
    return a, [(127.5, None)], f"MNI152 2009a white-matter probability (uint8), crop {a.shape} at {lo}"


def dom_mni_t1(crop):
    a, lo = mri_crop(T1_NAME, crop)
    return a, [(151.5, 201.5)], f"MNI152 2009a T1 (uint8), crop {a.shape} at {lo}, grey-matter band"


def make_domain(name, n, crop, force=False):
    """Write benchmarks/data/quality/<name>_<size>.npy (float32) if missing; return its
    description: dict(name, path, shape, intervals, note)."""
    builders = {"sphere": dom_sphere, "torus": dom_torus, "genus3": dom_genus3, "shell": dom_shell,
                "two_spheres": dom_two_spheres, "random": dom_random}
    is_mri = name.startswith("mni_")
    size = crop if is_mri else n
    path = os.path.join(DATA, f"{name}_{size}.npy")
    f, intervals, note = (dom_mni_wm if name == "mni_wm" else dom_mni_t1)(crop) if is_mri else builders[name](n)
    if force or not os.path.exists(path):
        os.makedirs(DATA, exist_ok=True)
        np.save(path, np.ascontiguousarray(f, dtype="<f4"))
    f32 = np.asarray(f, dtype=np.float32)
    for b in (b for iv in intervals for b in iv if b is not None):
        hits = int((f32 == np.float32(b)).sum())
        if hits:   # a bound on a grid value pinches the surface through that vertex (coincident nodes)
            print(f"[quality] WARNING {name}: {hits} grid values equal the bound {b:g}", flush=True)
            note += f"; {hits} grid values equal the bound {b:g}"
    return {"name": name, "path": path, "shape": list(f.shape), "intervals": intervals, "note": note}


def interval_str(iv):
    a, b = iv
    return f"{'(-inf' if a is None else '[' + format(a, 'g')}, {'inf)' if b is None else format(b, 'g') + ']'}"


# ----------------------------------------------------------------------------
# mesh statistics
# ----------------------------------------------------------------------------

def signed_volumes(P, T):
    """6 x signed volume, positive when (p1-p0, p2-p0, p3-p0) is right-handed (VTK / Gmsh)."""
    a = P[T[:, 0]]
    return np.einsum("ij,ij->i", np.cross(P[T[:, 1]] - a, P[T[:, 2]] - a), P[T[:, 3]] - a)


def dihedral_angles(P, T):
    """(m, 6) dihedral angles in degrees, one per edge, vectorised.

    With outward face normals n_k (face opposite vertex k), the dihedral angle at the
    edge shared by faces k and l is pi - angle(n_k, n_l).  Degenerate tets (a face of zero
    area) get 0 at the affected edges."""
    p = [P[T[:, k]] for k in range(4)]
    normals = []
    for k, (i, j, l) in enumerate(((1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1))):
        n = np.cross(p[j] - p[i], p[l] - p[i])
        side = np.einsum("ij,ij->i", n, p[k] - p[i])     # < 0 when n points away from p_k
        n *= -np.sign(side)[:, None]
        normals.append(n)
    norm = [np.linalg.norm(n, axis=1) for n in normals]
    out = np.empty((len(T), 6))
    for e, (k, l) in enumerate(((2, 3), (1, 3), (1, 2), (0, 3), (0, 2), (0, 1))):
        den = norm[k] * norm[l]
        with np.errstate(invalid="ignore", divide="ignore"):
            c = -np.einsum("ij,ij->i", normals[k], normals[l]) / den
        ang = np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))
        out[:, e] = np.where(den > 0, ang, 0.0)
    return out


def tet_stats(P, T):
    """Dihedral statistics of a tet mesh, computed in chunks of CHUNK tets."""
    P = np.asarray(P, dtype=np.float64)
    T = np.asarray(T, dtype=np.int64)
    nbins = int(round(180 / HIST_BIN))
    hist = np.zeros(nbins, dtype=np.int64)
    lo, hi = 180.0, 0.0
    below = dict.fromkeys(MIN_BELOW, 0)
    above = dict.fromkeys(MAX_ABOVE, 0)
    neg = zero = 0
    vol = 0.0
    for s in range(0, len(T), CHUNK):
        t = T[s:s + CHUNK]
        ang = dihedral_angles(P, t)
        tmin, tmax = ang.min(axis=1), ang.max(axis=1)
        lo, hi = min(lo, float(tmin.min())), max(hi, float(tmax.max()))
        hist += np.bincount(np.minimum((ang.ravel() / HIST_BIN).astype(np.int64), nbins - 1), minlength=nbins)
        for b in MIN_BELOW:
            below[b] += int((tmin < b).sum())
        for b in MAX_ABOVE:
            above[b] += int((tmax > b).sum())
        v = signed_volumes(P, t)
        neg += int((v < 0).sum())
        zero += int((v == 0).sum())
        vol += float(v.sum()) / 6.0
    m = len(T)
    cum = np.cumsum(hist)
    pct = {f"p{q}": float(np.searchsorted(cum, q / 100.0 * cum[-1]) * HIST_BIN + HIST_BIN / 2) for q in PCTS} if m else {}
    return {"tets": m, "points": int(len(P)), "min": lo if m else None, "max": hi if m else None, **pct,
            **{f"pct_min_below_{b}": 100.0 * below[b] / max(m, 1) for b in MIN_BELOW},
            **{f"pct_max_above_{b}": 100.0 * above[b] / max(m, 1) for b in MAX_ABOVE},
            "negative_volume": neg, "zero_volume": zero, "volume": vol,
            "hist_1deg": hist.reshape(180, -1).sum(axis=1).tolist()}


def boundary_surface(T):
    """Boundary triangles of a tet mesh (faces used by exactly one tet), oriented outward
    for positively oriented tets.  Returns (used point ids, triangles into them)."""
    faces = np.concatenate([T[:, [1, 2, 3]], T[:, [0, 3, 2]], T[:, [0, 1, 3]], T[:, [0, 2, 1]]])
    key = np.sort(faces, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    tri = faces[cnt[inv.ravel()] == 1]
    used, F = np.unique(tri, return_inverse=True)
    return used, F.reshape(-1, 3)


def winding_number(V, F, q):
    """Generalised winding number of the oriented triangle soup (V, F) at point q
    (Van Oosterom & Strackee solid angles): ~1 inside, ~0 outside."""
    a, b, c = V[F[:, 0]] - q, V[F[:, 1]] - q, V[F[:, 2]] - q
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    num = np.einsum("ij,ij->i", a, np.cross(b, c))
    den = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", b, c) * la
           + np.einsum("ij,ij->i", c, a) * lb)
    return float(np.sum(2.0 * np.arctan2(num, den)) / (4.0 * math.pi))


def cavity_hole_points(V, F, local=False):
    """One point inside every enclosed cavity of the domain bounded by (V, F).

    A connected component of the surface with negative enclosed (signed) volume is an
    inner shell: the region just across it is a cavity.  The hole point is the centroid
    of a large triangle of that shell moved 0.1 x its inradius along the outward normal,
    accepted when the winding number there is ~0 (outside the domain).  With `local`, the
    winding number is that of the shell alone, ~-1 in its cavity: the same test for a point
    that close to its shell, and linear instead of quadratic time on surfaces with
    thousands of cavities (whole MRI volumes)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    nv = len(V)
    rows = np.repeat(np.arange(len(F)), 3)
    g = coo_matrix((np.ones(len(rows)), (rows, F.ravel())), shape=(len(F), nv)).tocsr()
    ncomp, vlabel = connected_components(g.T @ g, directed=False)
    tlabel = vlabel[F[:, 0]]
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    cr = np.cross(b - a, c - a)
    vol6 = np.einsum("ij,ij->i", a, np.cross(b, c))
    comp_vol = np.bincount(tlabel, weights=vol6, minlength=ncomp) / 6.0
    area2 = np.linalg.norm(cr, axis=1)
    perim = np.linalg.norm(b - a, axis=1) + np.linalg.norm(c - b, axis=1) + np.linalg.norm(a - c, axis=1)
    inradius = area2 / np.maximum(perim, 1e-300)
    holes = []
    order = np.argsort(tlabel, kind="stable")
    start = np.concatenate([[0], np.cumsum(np.bincount(tlabel, minlength=ncomp))])
    for comp in np.flatnonzero(comp_vol < 0):
        cand = order[start[comp]:start[comp + 1]]
        for t in cand[np.argsort(-inradius[cand])][:5]:
            q = (a[t] + b[t] + c[t]) / 3.0 + 0.1 * inradius[t] * cr[t] / area2[t]
            if (abs(winding_number(V, F[cand], q) + 1.0) < 0.25 if local
                    else abs(winding_number(V, F, q)) < 0.25):
                holes.append(q)
                break
    return np.array(holes).reshape(-1, 3), int(ncomp), int((comp_vol < 0).sum())


# ----------------------------------------------------------------------------
# mesh I/O
# ----------------------------------------------------------------------------

def read_msh_tets(path):
    import meshio
    m = meshio.read(path)
    T = np.concatenate([c.data for c in m.cells if c.type == "tetra"])
    return np.asarray(m.points, dtype=np.float64), T.astype(np.int64)


def write_smesh(path, V, F, holes):
    """TetGen .smesh: nodes (0-based), triangle facets, hole points, no regions."""
    with open(path, "w") as f:
        f.write(f"# boundary of a tptd-mesh mesh\n{len(V)} 3 0 0\n")
        np.savetxt(f, np.column_stack([np.arange(len(V)), V]), fmt="%d %.17g %.17g %.17g")
        f.write(f"{len(F)} 0\n")
        np.savetxt(f, np.column_stack([np.full(len(F), 3), F]), fmt="%d")
        f.write(f"{len(holes)}\n")
        if len(holes):
            np.savetxt(f, np.column_stack([np.arange(len(holes)), holes]), fmt="%d %.17g %.17g %.17g")
        f.write("0\n")


def read_table(path, ncols):
    """First `ncols` columns of a TetGen .node/.ele file (header line skipped, '#' comments)."""
    try:
        import pandas as pd
        df = pd.read_csv(path, sep=r"\s+", comment="#", skiprows=1, header=None, usecols=range(ncols), engine="c")
        return df.to_numpy()
    except ImportError:
        return np.loadtxt(path, comments="#", skiprows=1, usecols=range(ncols))


def read_tetgen(prefix):
    node = read_table(prefix + ".node", 4)
    ele = read_table(prefix + ".ele", 5).astype(np.int64)
    base = int(node[0, 0])
    P = np.zeros((int(node[:, 0].max()) + 1 - base, 3))
    P[node[:, 0].astype(np.int64) - base] = node[:, 1:4]
    return P, ele[:, 1:5] - base


# ----------------------------------------------------------------------------
# child processes
# ----------------------------------------------------------------------------

def run_child(cmd, log_prefix, timeout, mem_limit_gb=None, cwd=None):
    """Run cmd as a fresh process in its own session, stdout/stderr to log files, timed
    with perf_counter.  On timeout the whole process group is killed.  Returns dict(status
    'ok' | 'timeout' | 'crash' | 'failed', wall, rc, detail)."""
    def limit():
        if mem_limit_gb:
            lim = int(mem_limit_gb * 2 ** 30)
            resource.setrlimit(resource.RLIMIT_AS, (lim, lim))

    with open(log_prefix + ".stdout", "wb") as fo, open(log_prefix + ".stderr", "wb") as fe:
        t0 = time.perf_counter()
        p = subprocess.Popen(cmd, stdout=fo, stderr=fe, cwd=cwd, start_new_session=True, preexec_fn=limit)
        try:
            rc = p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
            return {"status": "timeout", "wall": time.perf_counter() - t0, "rc": None,
                    "detail": f"timeout after {timeout:g} s (killed)"}
        wall = time.perf_counter() - t0
    if rc == 0:
        return {"status": "ok", "wall": wall, "rc": 0, "detail": ""}
    tail = (read_tail(log_prefix + ".stderr") + " " + read_tail(log_prefix + ".stdout")).strip()
    if rc < 0:
        name = signal.Signals(-rc).name if -rc in signal.valid_signals() else str(-rc)
        return {"status": "crash", "wall": wall, "rc": rc, "detail": f"{name}: {tail}"[:300]}
    return {"status": "failed", "wall": wall, "rc": rc, "detail": f"exit {rc}: {tail}"[:300]}


def read_tail(path, n=400):
    try:
        with open(path, "rb") as f:
            f.seek(0, 2)
            f.seek(max(0, f.tell() - n))
            return " ".join(f.read().decode("utf-8", "replace").split())
    except OSError:
        return ""


def has_quality_flag(binary):
    try:
        h = subprocess.run([binary, "--help"], capture_output=True, text=True, timeout=30).stdout
    except (OSError, subprocess.TimeoutExpired):
        return False
    return "--quality" in h


# ----------------------------------------------------------------------------
# the tools
# ----------------------------------------------------------------------------

def run_ours(args, dom, iv, tag, quality, target=None):
    """tptd-mesh (ctd) on one domain/interval, with `--quality` if `quality`, aiming at
    `target` = (min, max) dihedral angles if given; returns (row, points, tets)."""
    label = f"{tag}_ours{'_quality' if quality else ''}"
    tool = "ours --quality" if quality else "ours"
    extra = []
    if target:
        extra = ["--min-angle", f"{target[0]:g}", "--max-angle", f"{target[1]:g}"]
        label += f"_{target[0]:g}_{target[1]:g}"
        tool += " " + " ".join(extra)
    msh, rep = os.path.join(OUT, label + ".msh"), os.path.join(OUT, label + ".report.json")
    cmd = [args.bin, dom["path"]]
    if iv[0] is not None:
        cmd += ["--alpha", repr(float(iv[0]))]
    if iv[1] is not None:
        cmd += ["--beta", repr(float(iv[1]))]
    cmd += ["-o", msh, "--report", rep] + (["--quality"] if quality else []) + extra
    r = run_child(cmd, os.path.join(OUT, label), args.timeout)
    row = {"tool": tool, "command": " ".join(cmd), **r}
    P = T = None
    if r["status"] == "ok":
        with open(rep) as f:
            report = json.load(f)
        row["report"] = {k: report.get(k) for k in ("betti", "boundary_triangles", "timings_seconds",
                                                   "dihedral_degrees", "volume", "nodes", "tets")}
        P, T = read_msh_tets(msh)
        row.update(tet_stats(P, T))
    if not args.keep_outputs and os.path.exists(msh):
        os.remove(msh)
    return row, P, T


def run_tetgen(args, smesh, switches, tag):
    """tetgen <switches> on a copy of the surface in its own folder."""
    d = os.path.join(OUT, f"{tag}_tetgen_{switches.replace('/', '_').replace('.', '')}")
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    shutil.copy(smesh, os.path.join(d, "surf.smesh"))
    cmd = [args.tetgen, switches, "surf.smesh"]
    # line-buffered stdout so TetGen's last message survives an abort (SIGABRT)
    line_buf = ["stdbuf", "-oL"] if shutil.which("stdbuf") else []
    r = run_child(line_buf + cmd, os.path.join(d, "log"), args.timeout, args.mem_limit_gb, cwd=d)
    row = {"tool": f"tetgen {switches}", "command": " ".join(cmd), **r}
    if r["status"] == "ok":
        try:
            P, T = read_tetgen(os.path.join(d, "surf.1"))
            row.update(tet_stats(P, T))
        except (OSError, ValueError) as e:
            row.update(status="failed", detail=f"unreadable output: {e}"[:300])
    if not args.keep_outputs:
        for ext in ("node", "ele", "face", "edge", "smesh"):
            p = os.path.join(d, "surf.1." + ext)
            if os.path.exists(p):
                os.remove(p)
    return row


def run_ftetwild(args, V, F, tag):
    """pytetwild in a child process (this script, --ftetwild-worker)."""
    base = os.path.join(OUT, f"{tag}_ftetwild")
    np.savez(base + "_in.npz", V=V, F=F.astype(np.int32))
    cmd = [sys.executable, os.path.abspath(__file__), "--ftetwild-worker", base + "_in.npz", base + "_out.npz",
           "--ftetwild-edge", str(args.ftetwild_edge)]
    r = run_child(cmd, base, args.ftetwild_timeout, cwd=OUT)     # fTetWild drops __tracked_surface.stl in cwd
    edge = (f"edge_length_abs={args.ftetwild_edge:g}" if args.ftetwild_edge > 0 else "edge_length_fac=0.05")
    row = {"tool": "fTetWild", "command": f"pytetwild.tetrahedralize(V, F, {edge}, optimize=True, "
                                          "vtk_ordering=True)", **r}
    if r["status"] == "ok":
        with np.load(base + "_out.npz") as z:
            P, T, row["process_wall"] = z["V"], z["T"], r["wall"]
            row["wall"] = float(z["seconds"])
        row.update(tet_stats(P, T))
    for p in (base + "_in.npz", base + "_out.npz"):
        if os.path.exists(p) and not args.keep_outputs:
            os.remove(p)
    return row


def median_run(runs):
    """The run of median smallest angle among `runs` of one peer (a run that did not finish
    counts as the lowest), with every run's smallest angle (or status) and time under
    "runs". fTetWild's result changes from run to run, so one run says little."""
    if len(runs) == 1:
        return runs[0]
    key = [(r["min"] if r["status"] == "ok" else -math.inf) for r in runs]
    order = sorted(range(len(runs)), key=lambda i: key[i])
    row = dict(runs[order[len(runs) // 2]])
    row["runs"] = [{"status": r["status"], "min": r.get("min"), "max": r.get("max"), "tets": r.get("tets"),
                    "wall": r["wall"]} for r in runs]
    return row


def ftetwild_worker(inp, out, edge):
    """Child process: load (V, F), time pytetwild.tetrahedralize only, save (V, T, seconds)."""
    import pytetwild
    with np.load(inp) as z:
        V, F = z["V"].astype(np.float64), z["F"].astype(np.int32)
    kw = {"edge_length_abs": edge} if edge > 0 else {"edge_length_fac": 0.05}
    t0 = time.perf_counter()
    P, T = pytetwild.tetrahedralize(V, F, optimize=True, vtk_ordering=True, quiet=True, **kw)
    np.savez(out, V=P, T=T, seconds=time.perf_counter() - t0)


# ----------------------------------------------------------------------------
# one domain / interval
# ----------------------------------------------------------------------------

def bench_interval(args, dom, k, iv, with_quality):
    tag = f"{dom['name']}_{dom['shape'][0]}_iv{k}"
    ivs = interval_str(iv)
    rows = []

    def add(row):
        row.update(domain=dom["name"], interval=ivs)
        rows.append(row)
        print(f"  {row['tool']:<22} {row['status']:<8} {row['wall']:8.2f} s  "
              + (f"{row['tets']:>9,} tets  min {row['min']:6.2f}  max {row['max']:6.2f}"
                 if row["status"] == "ok" else row["detail"][:120]), flush=True)

    print(f"\n[quality] {dom['name']} {tuple(dom['shape'])} {ivs}", flush=True)
    base, P, T = run_ours(args, dom, iv, tag, False)
    add(base)
    if with_quality:
        add(run_ours(args, dom, iv, tag, True)[0])
        for target in args.targets:
            add(run_ours(args, dom, iv, tag, True, target)[0])
    if T is None or (args.no_tetgen and args.no_ftetwild):
        return rows
    used, F = boundary_surface(T)
    V = P[used]
    holes, ncomp, ninner = cavity_hole_points(V, F)
    base["surface"] = {"points": int(len(V)), "triangles": int(len(F)), "components": ncomp,
                       "inner_shells": ninner, "hole_points": int(len(holes))}
    smesh = os.path.join(OUT, tag + "_surf.smesh")
    write_smesh(smesh, V, F, holes)
    if not args.no_tetgen:
        for sw in args.tetgen_switches:
            add(run_tetgen(args, smesh, sw, tag))
    if not args.no_ftetwild:
        add(median_run([run_ftetwild(args, V, F, tag) for _ in range(args.ftetwild_runs)]))
    if not args.keep_outputs:
        os.remove(smesh)
    return rows


def add_volume_change(rows):
    """Each successful row's total volume against our plain mesh of the same interval, in %."""
    base = next((r for r in rows if r["tool"] == "ours" and r["status"] == "ok"), None)
    for r in rows:
        if base and r["status"] == "ok" and base.get("volume"):
            r["volume_change_pct"] = 100.0 * (r["volume"] - base["volume"]) / abs(base["volume"])


# ----------------------------------------------------------------------------
# report
# ----------------------------------------------------------------------------

def sh(cmd):
    try:
        return subprocess.run(cmd, shell=True, capture_output=True, text=True, timeout=30).stdout.strip()
    except (OSError, subprocess.TimeoutExpired):
        return ""


def machine_info(args):
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    mem = next((l.split(":", 1)[1].strip() for l in open("/proc/meminfo") if l.startswith("MemTotal")), "?")

    def version(dist):      # without importing it (pytetwild imports pyvista + vtk: seconds)
        from importlib import metadata
        try:
            return metadata.version(dist)
        except metadata.PackageNotFoundError:
            return None
    return {"date": datetime.datetime.now().isoformat(timespec="seconds"), "nproc": os.cpu_count(),
            "cpu": cpu, "mem_total": mem, "uname": platform.platform(), "python": platform.python_version(),
            "loadavg_start": os.getloadavg(), "git_head": sh(f"git -C {REPO} rev-parse --short HEAD"),
            "tptd_mesh": sh(f"{args.bin} --version"), "tetgen": sh("dpkg-query -W -f='${Version}' tetgen"),
            "pytetwild": version("pytetwild") if not args.no_ftetwild else None,
            "numpy": np.__version__, "meshio": version("meshio")}


def fmt(x, spec, dash="–"):
    return dash if x is None else format(x, spec)


def pct(x):
    return "–" if x is None else f"{x:+.2f} %"


def render_md(p):
    m = p["machine"]
    L = ["# Element quality: tptd-mesh vs TetGen and fTetWild\n",
         f"Generated {m['date']} by `benchmarks/quality.py` (git `{m['git_head']}`, {m['tptd_mesh']}). "
         f"Command: `{p['command']}`. Total {p['total_seconds']:.0f} s. "
         f"`--quality` {'available' if p['has_quality'] else 'not available in this binary: only the baseline'}.\n"]
    if m["loadavg_start"][0] > 0.5 * (m["nproc"] or 1):
        L.append(f"> **Loaded machine**: load average {m['loadavg_start'][0]:.1f} at start, "
                 f"{m['loadavg_end'][0]:.1f} at end on {m['nproc']} CPUs; times are indicative only.\n")
    L.append("Dihedral angles in degrees over all six edges of every tet; `% <10°` / `% <15°` = share of tets "
             "whose smallest dihedral angle is below 10° / 15°, `% >155°` = share whose largest is above 155°. "
             "`volume vs ours` = total volume against our plain mesh of the same interval. "
             "Time = wall seconds of a fresh process (ours: read + mesh + analysis + .msh write; TetGen: read "
             "+ mesh + write), for fTetWild the `tetrahedralize` call alone. TetGen and fTetWild mesh the "
             "boundary surface of *our* (baseline) mesh.\n")
    L.append("| domain | interval | tool | tets | min° | max° | % <10° | % <15° | % >155° | volume vs ours | time s | note |")
    L.append("|---|---|---|--:|--:|--:|--:|--:|--:|--:|--:|---|")
    for r in p["rows"]:
        if r["status"] == "ok":
            L.append(f"| {r['domain']} | {r['interval']} | {r['tool']} | {r['tets']:,} | {r['min']:.2f} | "
                     f"{r['max']:.2f} | {r['pct_min_below_10']:.2f} | {r['pct_min_below_15']:.2f} | "
                     f"{r['pct_max_above_155']:.2f} | {pct(r.get('volume_change_pct'))} | "
                     f"{r['wall']:.2f} | {note(r)} |")
        else:
            L.append(f"| {r['domain']} | {r['interval']} | {r['tool']} | **{r['status']}** | | | | | | | "
                     f"{r['wall']:.2f} | {md_escape(r['detail'][:160])} |")
    L.append("\n## Domains\n")
    L.append("| domain | grid | intervals | ours: Betti (b0, b1, b2) | boundary triangles (cavities) | what |")
    L.append("|---|---|---|---|---|---|")
    for d in p["domains"]:
        base = next((r for r in p["rows"] if r["domain"] == d["name"] and r["tool"] == "ours"), {})
        s = base.get("surface") or {}
        betti = (base.get("report") or {}).get("betti")
        L.append(f"| {d['name']} | {'×'.join(map(str, d['shape']))} | "
                 f"{', '.join(interval_str(iv) for iv in d['intervals'])} | {tuple(betti) if betti else '–'} | "
                 f"{fmt(s.get('triangles'), ',')} ({fmt(s.get('hole_points'), 'd')}) | {d['note']} |")
    L.append("\n## Percentiles of the dihedral angles (successful runs)\n")
    L.append("| domain | interval | tool | " + " | ".join(f"p{q}" for q in PCTS) + " | % min <5° | % max >165° |")
    L.append("|---|---|---|" + "--:|" * (len(PCTS) + 2))
    for r in p["rows"]:
        if r["status"] == "ok":
            L.append(f"| {r['domain']} | {r['interval']} | {r['tool']} | "
                     + " | ".join(f"{r[f'p{q}']:.1f}" for q in PCTS)
                     + f" | {r['pct_min_below_5']:.2f} | {r['pct_max_above_165']:.2f} |")
    L.append("\n## Commands\n")
    L.append("- ours: `tptd-mesh IN.npy [--alpha A] [--beta B] -o OUT.msh --report R.json [--quality "
             "[--min-angle MIN --max-angle MAX]]`")
    L.append(f"- TetGen: `tetgen {' | '.join(p['tetgen_switches'])} surf.smesh` (`F`: no .face/.edge output); "
             "surf.smesh = boundary of our mesh plus one hole point per enclosed cavity; address space limited "
             f"to {p['mem_limit_gb']:g} GB; timeout {p['timeout']:g} s")
    runs = p.get("ftetwild_runs", 1)
    L.append(f"- fTetWild: `{p['ftetwild_call']}` (all cores), timeout {p['ftetwild_timeout']:g} s"
             + (f"; {runs} runs per domain, the row is the run of median smallest angle" if runs > 1 else ""))
    L.append("\n## Machine\n")
    L.append(f"- `nproc`: {m['nproc']}\n- CPU: {m['cpu']}\n- memory: {m['mem_total']}\n- {m['uname']}, "
             f"Python {m['python']}, numpy {m['numpy']}, meshio {m['meshio']}, TetGen (Debian) {m['tetgen']}, "
             f"pytetwild {m['pytetwild']}\n- load average at start {tuple(round(x, 2) for x in m['loadavg_start'])}, "
             f"at end {tuple(round(x, 2) for x in m['loadavg_end'])}")
    return "\n".join(L) + "\n"


def note(r):
    bits = []
    if r["tool"] == "fTetWild" and r.get("process_wall") is not None:
        bits.append(f"process {r['process_wall']:.1f} s")
    if r.get("runs"):
        mins = ", ".join(f"{x['min']:.2f}°" if x["status"] == "ok" else x["status"] for x in r["runs"])
        bits.append(f"median of {len(r['runs'])} runs (min: {mins})")
    v = r.get("negative_volume", 0)
    if 0 < v < r["tets"]:
        bits.append(f"{v:,} negatively oriented")
    if r.get("zero_volume"):
        bits.append(f"{r['zero_volume']:,} zero volume")
    return "; ".join(bits)


def md_escape(s):
    return s.replace("|", "\\|").replace("\n", " ")


def plot_hist(payload, path, domain=None):
    """Dihedral histogram (1° bins, log y) of ours before / after --quality, summed over
    all domains or one domain."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 4.5))
    edges = np.arange(181)
    for tool, colour in (("ours", "tab:blue"), ("ours --quality", "tab:orange")):
        rows = [r for r in payload["rows"] if r["tool"] == tool and r["status"] == "ok"
                and (domain is None or r["domain"] == domain)]
        if not rows:
            continue
        h = np.sum([r["hist_1deg"] for r in rows], axis=0)
        lo, hi = min(r["min"] for r in rows), max(r["max"] for r in rows)
        label = f"{'after' if 'quality' in tool else 'before'} ({tool}): {int(h.sum()):,} angles, " \
                f"min {lo:.2f}°, max {hi:.2f}°"
        ax.stairs(h, edges, color=colour, label=label, linewidth=1.5)
    ax.set_yscale("log")
    ax.set_xlim(0, 180)
    ax.set_xticks(range(0, 181, 15))
    for x in (15, 155):
        ax.axvline(x, color="grey", linestyle=":", linewidth=1)
    ax.set_xlabel("dihedral angle (degrees), 1° bins")
    ax.set_ylabel("count")
    ax.set_title(f"tptd-mesh dihedral angles, {domain or 'all domains'}"
                 + ("" if payload["has_quality"] else " (--quality not available yet)"))
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ----------------------------------------------------------------------------

def parse_args():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=int, default=32, help="grid size N of the analytic domains (default 32)")
    ap.add_argument("--mri-crop", type=int, default=40, help="edge of the central MNI crops (default 40)")
    ap.add_argument("--domains", default=None, help="comma-separated subset of " + ",".join(ALL_DOMAINS))
    ap.add_argument("--quick", action="store_true",
                    help="smoke test: N = 32, sphere + torus, timeouts 15 s, *_quick outputs")
    ap.add_argument("--bin", default=os.environ.get("TPTD_BIN", os.path.join(REPO, "target", "release", "tptd-mesh")))
    ap.add_argument("--tetgen", default=shutil.which("tetgen") or "/usr/bin/tetgen")
    ap.add_argument("--tetgen-switches", default="-pq1.2F,-pq1.2/10F",
                    help="comma-separated TetGen switch sets (default -pq1.2F,-pq1.2/10F)")
    ap.add_argument("--targets", default="",
                    help="comma-separated MIN/MAX dihedral targets: one more row of ours --quality "
                         "--min-angle MIN --max-angle MAX per pair (e.g. 20/150,25/145)")
    ap.add_argument("--no-tetgen", action="store_true")
    ap.add_argument("--no-ftetwild", action="store_true")
    ap.add_argument("--timeout", type=float, default=None, help="per tptd-mesh / TetGen run, s (default 60)")
    ap.add_argument("--ftetwild-timeout", type=float, default=None, help="per fTetWild run, s (default 60)")
    ap.add_argument("--ftetwild-runs", type=int, default=1,
                    help="fTetWild runs per domain; the row is the run of median smallest angle (default 1)")
    ap.add_argument("--ftetwild-edge", type=float, default=1.0,
                    help="fTetWild edge_length_abs in voxels (default 1.0); 0: its default edge_length_fac=0.05")
    ap.add_argument("--mem-limit-gb", type=float, default=8.0, help="address-space limit for TetGen (default 8)")
    ap.add_argument("--hist-domain", default=None, help="histogram of one domain instead of all")
    ap.add_argument("--out", default=None, help="output prefix (default benchmarks/quality_results)")
    ap.add_argument("--hist", default=None, help="histogram PNG (default benchmarks/quality_hist.png)")
    ap.add_argument("--keep-outputs", action="store_true", help="keep meshes in benchmarks/out/quality/")
    ap.add_argument("--force", action="store_true", help="regenerate the volumes")
    ap.add_argument("--ftetwild-worker", nargs=2, metavar=("IN", "OUT"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    quick = "_quick" if args.quick else ""
    if args.quick:
        args.size = 32
    args.domains = (args.domains.split(",") if args.domains else QUICK_DOMAINS if args.quick else ALL_DOMAINS)
    unknown = set(args.domains) - set(ALL_DOMAINS)
    if unknown:
        ap.error(f"unknown domain(s) {sorted(unknown)}; choose from {ALL_DOMAINS}")
    args.timeout = args.timeout or (QUICK_TIMEOUT if args.quick else TIMEOUT)
    args.ftetwild_timeout = args.ftetwild_timeout or (QUICK_TIMEOUT if args.quick else TIMEOUT)
    args.tetgen_switches = [s for s in args.tetgen_switches.split(",") if s]
    try:
        args.targets = [tuple(float(x) for x in t.split("/")) for t in args.targets.split(",") if t]
    except ValueError:
        ap.error(f"--targets: expected MIN/MAX pairs like 20/150, got {args.targets!r}")
    if args.ftetwild_runs < 1:
        ap.error(f"--ftetwild-runs: expected at least 1, got {args.ftetwild_runs}")
    if any(len(t) != 2 or not 0 < t[0] < t[1] < 180 for t in args.targets):
        ap.error(f"--targets: each pair needs 0 < MIN < MAX < 180, got {args.targets}")
    args.out = args.out or os.path.join(HERE, "quality_results" + quick)
    args.hist = args.hist or os.path.join(HERE, f"quality_hist{quick}.png")
    return args


def main():
    args = parse_args()
    if args.ftetwild_worker:
        return ftetwild_worker(*args.ftetwild_worker, args.ftetwild_edge)
    if not os.access(args.bin, os.X_OK):
        sys.exit(f"[quality] {args.bin} not found: cargo build --release (or --bin PATH)")
    if not args.no_tetgen and not os.access(args.tetgen, os.X_OK):
        sys.exit("[quality] tetgen not found: apt-get install -y tetgen (or --no-tetgen)")
    os.makedirs(OUT, exist_ok=True)
    with_quality = has_quality_flag(args.bin)
    machine = machine_info(args)
    command = "python3 benchmarks/quality.py " + " ".join(sys.argv[1:])
    print(f"[quality] {machine['date']}  {machine['nproc']} CPUs  load {machine['loadavg_start']}  "
          f"--quality {'found' if with_quality else 'not found'} in {args.bin}", flush=True)
    t0 = time.perf_counter()
    domains, rows = [], []
    for name in args.domains:
        try:
            dom = make_domain(name, args.size, args.mri_crop, args.force)
        except FileNotFoundError as e:
            print(f"[quality] skipping {name}: {e}", flush=True)
            continue
        domains.append(dom)
        for k, iv in enumerate(dom["intervals"]):
            iv_rows = bench_interval(args, dom, k, iv, with_quality)
            add_volume_change(iv_rows)
            rows += iv_rows
    machine["loadavg_end"] = os.getloadavg()
    edge = f"edge_length_abs={args.ftetwild_edge:g}" if args.ftetwild_edge > 0 else "edge_length_fac=0.05"
    payload = {"command": command, "machine": machine, "binary": args.bin, "has_quality": with_quality,
               "size": args.size, "mri_crop": args.mri_crop, "timeout": args.timeout,
               "ftetwild_timeout": args.ftetwild_timeout, "ftetwild_runs": args.ftetwild_runs,
               "mem_limit_gb": args.mem_limit_gb,
               "tetgen_switches": args.tetgen_switches,
               "ftetwild_call": f"pytetwild.tetrahedralize(V, F, {edge}, optimize=True, vtk_ordering=True)",
               "domains": domains, "rows": rows, "total_seconds": time.perf_counter() - t0}
    with open(args.out + ".json", "w") as f:
        json.dump(payload, f, indent=1)
    with open(args.out + ".md", "w") as f:
        f.write(render_md(payload))
    plot_hist(payload, args.hist, args.hist_domain)
    print(f"\n[quality] wrote {args.out}.md, {args.out}.json, {args.hist}  "
          f"({payload['total_seconds']:.0f} s)", flush=True)


if __name__ == "__main__":
    sys.exit(main())
