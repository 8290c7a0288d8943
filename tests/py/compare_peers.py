#!/usr/bin/env python3
"""Meshes small domains with tptd-mesh (ctd, ctd --quality), TetGen and fTetWild and judges
every mesh with the library checker (`tptd-mesh --inspect ... --volume V --json J`); called by
tests/compare_peers.rs, which asserts on the JSON written here.

usage: compare_peers.py --bin TPTD_MESH --out DIR --json FILE [--peer-timeout S]
                        [--budget S] [--domains a,b,...]

Domains (unit spacing; levels off round numbers so that no grid value equals a bound):
torus, genus 3, two balls 0.3 voxel apart, a thin spherical shell (two-sided interval), a
seeded smooth random field (grids 20^3-24^3) and a 24^3 crop of the MNI152 white-matter
template (nilearn): at 32^3, TetGen and fTetWild on the crop need minutes here.

Per domain:
  ours      `tptd-mesh vol.npy [--alpha A] [--beta B] -o ctd.msh --check`, and with `--quality`
  surfaces  "ours": the boundary of our ctd --quality mesh (of the ctd mesh if that failed):
            on the level sets like ctd's, and better shaped, which spares TetGen minutes;
            "mc": marching cubes (scikit-image, Lewiner)
            of each finite bound on the volume padded by one layer outside the interval, so the
            surface is closed (where the domain meets the grid box it closes up to a voxel
            outside it, which the checker reports as `outside_grid`); each oriented outward,
            with one hole point per enclosed cavity
  TetGen    the PyPI `tetgen` package, `pq1.2` and `pq1.2/10` on our surface, `pq1.2` on the
            marching-cubes one (not on the MNI crop's: over a minute)
  fTetWild  `pytetwild.tetrahedralize(V, F, edge_length_abs=1.5, epsilon=3e-3, optimize=True,
            vtk_ordering=True, num_threads=1)` on both surfaces
Each peer run is a child process (this script with --worker) under --peer-timeout; a crash,
failure or timeout is recorded in its row, never raised. Runs that would start after --budget
seconds are recorded as `skipped` so the whole run stays bounded on a loaded machine.

The JSON: {"domains": [{name, shape, alpha, beta, note, reference_betti, rows: [{tool,
surface, status, wall, detail, tets, min, max, valid, problems, betti, matches_reference,
level_max_distance}]}], "total_seconds", ...}. A table is printed too.
"""
import argparse
import json
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(REPO, "benchmarks"))

import quality as q  # noqa: E402  (benchmarks/quality.py: domains, surfaces, child processes)

LEVEL = 0.0137          # offset of every analytic level: away from grid values and saddles
MNI_LEVEL = 127.0135    # on uint8 data: not an integer, not k + 0.5
SEED = 20240611
MNI_CROP = 24
FTETWILD_EDGE = 1.5     # voxels: coarse-ish
FTETWILD_EPSILON = 3e-3  # envelope / bbox diagonal (default 1e-3): about 3x faster here


# ----------------------------------------------------------------------------
# domains: (volume, alpha, beta, note); None = unbounded. Each takes the grid size (the
# crop's for the MNI template); the defaults are the test's sizes (benchmarks/compare.py
# calls them at larger ones).
# ----------------------------------------------------------------------------

def dom_torus(n=20):
    f, _, note = q.dom_torus(n)
    return f, None, LEVEL, note


def dom_genus3(n=24):
    f, _, note = q.dom_genus3(n)
    return f, None, LEVEL, note


def dom_two_spheres(n=20):
    f, _, note = q.dom_two_spheres(n, gap=0.3)
    return f, None, LEVEL, note


def dom_shell(n=20):
    f, [(a, b)], note = q.dom_shell(n, t=0.6)
    return f, a + LEVEL, b + LEVEL, note


def dom_random(n=20):
    """Band-limited Gaussian noise, correlation 3 voxels: smooth at the voxel scale. Plain ctd
    on fields rough at the voxel scale can put boundary triangles more than half a voxel off
    the level set, which `--check` rejects; this field keeps our meshes checkable."""
    from make_data import band_limited_noise
    corr = 3.0
    g = band_limited_noise(n, corr, np.random.default_rng(SEED)).astype(np.float64)
    x, y, z = q.grid(n)
    r = np.sqrt(x ** 2 + y ** 2 + z ** 2)
    f = g + np.maximum(0.0, r - 0.38 * n)
    return f, None, LEVEL, f"Gaussian noise, correlation {corr:g} voxel, seed {SEED}, + max(0, r - 0.38 N)"


def dom_mni(n=MNI_CROP):
    a, lo = q.mri_crop(q.WM_NAME, n)
    return a, MNI_LEVEL, None, f"MNI152 2009a white-matter probability (uint8), {n}^3 crop at {lo}"


DOMAINS = {"torus": dom_torus, "genus3": dom_genus3, "two_spheres": dom_two_spheres,
           "shell": dom_shell, "random": dom_random, "mni_wm": dom_mni}


# ----------------------------------------------------------------------------
# surfaces
# ----------------------------------------------------------------------------

def orient_outward(V, F):
    """Flips every triangle when the enclosed signed volume is negative."""
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return F[:, ::-1].copy() if np.einsum("ij,ij->i", a, np.cross(b, c)).sum() < 0 else F


def mc_surface(f, alpha, beta):
    """Marching cubes of each finite bound on f padded by one layer outside [alpha, beta];
    every level's triangles oriented out of the interval's domain."""
    from skimage.measure import marching_cubes
    f = np.asarray(f, dtype=np.float64)
    lo, hi = float(f.min()), float(f.max())
    pad = hi + 1.0 if beta is not None else lo - 1.0
    g = np.pad(f, 1, constant_values=pad)
    Vs, Fs, off = [], [], 0
    for level, outward_up in ((beta, True), (alpha, False)):
        if level is None:
            continue
        V, F, _, _ = marching_cubes(g, level, method="lewiner", allow_degenerate=False)
        V = V.astype(np.float64)
        # outward: towards increasing f at beta, decreasing f at alpha
        a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
        n = np.cross(b - a, c - a)
        grad = np.stack(np.gradient(g), axis=-1)
        idx = np.clip(np.rint((a + b + c) / 3.0).astype(int), 0, np.array(g.shape) - 1)
        s = np.einsum("ij,ij->i", n, grad[idx[:, 0], idx[:, 1], idx[:, 2]]).sum()
        if (s > 0) != outward_up:
            F = F[:, ::-1]
        Vs.append(V - 1.0)
        Fs.append(F + off)
        off += len(V)
    return np.concatenate(Vs), np.concatenate(Fs).astype(np.int64)


def our_surface(msh):
    P, T = q.read_msh_tets(msh)
    used, F = q.boundary_surface(T)
    return P[used], orient_outward(P[used], F)


# ----------------------------------------------------------------------------
# child processes
# ----------------------------------------------------------------------------

def write_tetgen_files(prefix, P, T):
    """TetGen .node/.ele, 0-based."""
    with open(prefix + ".node", "w") as f:
        f.write(f"{len(P)} 3 0 0\n")
        np.savetxt(f, np.column_stack([np.arange(len(P)), P]), fmt="%d %.17g %.17g %.17g")
    with open(prefix + ".ele", "w") as f:
        f.write(f"{len(T)} 4 0\n")
        np.savetxt(f, np.column_stack([np.arange(len(T)), T]), fmt="%d")


def worker(kind, inp, prefix, param):
    """Child process: mesh the surface in `inp` with TetGen (`param` = switches) or fTetWild
    (`param` = edge length); write `prefix`.node/.ele and `prefix`.seconds."""
    with np.load(inp) as z:
        V, F, holes = z["V"].astype(np.float64), z["F"].astype(np.int32), z["holes"]
    t0 = time.perf_counter()
    if kind == "tetgen":
        import tetgen
        tg = tetgen.TetGen(V, F)
        for h in holes:
            tg.add_hole([float(x) for x in h])
        P, T = tg.tetrahedralize(switches=param)[:2]
    else:
        import pytetwild
        P, T = pytetwild.tetrahedralize(V, F, edge_length_abs=float(param), optimize=True,
                                        vtk_ordering=True, quiet=True, num_threads=1,
                                        epsilon=FTETWILD_EPSILON)
    seconds = time.perf_counter() - t0
    if len(T) == 0:
        sys.exit("no tetrahedra")
    write_tetgen_files(prefix, np.asarray(P), np.asarray(T))
    with open(prefix + ".seconds", "w") as f:
        f.write(repr(seconds))


# ----------------------------------------------------------------------------
# one domain
# ----------------------------------------------------------------------------

def bounds_args(alpha, beta):
    out = []
    if alpha is not None:
        out += ["--alpha", repr(float(alpha))]
    if beta is not None:
        out += ["--beta", repr(float(beta))]
    return out


def run_domain(args, name, t_start):
    f, alpha, beta, note = DOMAINS[name]()
    d = os.path.join(args.out, name)
    os.makedirs(d, exist_ok=True)
    vol = os.path.join(d, "vol.npy")
    np.save(vol, np.ascontiguousarray(f))
    b = bounds_args(alpha, beta)
    rows, meshes = [], []       # meshes: (row, file) to inspect

    def ours(tool, extra, out):
        cmd = [args.bin, vol, *b, "-o", out, "--check", "-q", *extra]
        r = q.run_child(cmd, out[:-4], args.ours_timeout)
        row = {"tool": tool, "surface": "-", "command": " ".join(cmd), **r}
        rows.append(row)
        if r["status"] == "ok":
            meshes.append((row, out))
        return r["status"] == "ok"

    ours_ok = ours("ctd", [], os.path.join(d, "ctd.msh"))
    ours("ctd --quality", ["--quality"], os.path.join(d, "ctd_quality.msh"))

    surfaces = {}
    src = next((m for r, m in meshes if r["tool"] == "ctd --quality"), None) or (
        os.path.join(d, "ctd.msh") if ours_ok else None)
    if src:
        surfaces["ours"] = our_surface(src)
    surfaces["mc"] = mc_surface(f, alpha, beta)
    runs = []
    for sname, (V, F) in surfaces.items():
        holes = q.cavity_hole_points(V, F)[0]
        npz = os.path.join(d, f"surf_{sname}.npz")
        np.savez(npz, V=V, F=F, holes=holes)
        # TetGen -pq1.2 multiplies the tets of a marching-cubes surface: once there, and not on
        # the MNI crop's (over a minute here)
        switches = ["pq1.2", "pq1.2/10"] if sname == "ours" else [] if name == "mni_wm" else ["pq1.2"]
        runs += [("tetgen", f"tetgen -{sw}", sname, npz, sw) for sw in switches]
        runs.append(("ftetwild", "fTetWild", sname, npz, repr(FTETWILD_EDGE)))
    jobs = []
    for kind, tool, sname, npz, param in runs:
        prefix = os.path.join(d, f"{kind}_{sname}_{param.replace('/', '_').replace('.', '')}")
        row = {"tool": tool, "surface": sname}
        rows.append(row)
        cmd = [sys.executable, os.path.abspath(__file__), "--worker", kind, npz, prefix, param]
        jobs.append((row, cmd, prefix, d))
    return {"name": name, "shape": list(f.shape), "dtype": str(f.dtype), "alpha": alpha, "beta": beta,
            "note": note, "our_surface": src and os.path.basename(src), "rows": rows,
            "vol": vol, "bounds": b, "meshes": meshes, "jobs": jobs}


def run_peer(args, job, t_start):
    row, cmd, prefix, d = job
    if time.perf_counter() - t_start > args.budget:
        row.update(status="skipped", wall=0.0, detail=f"run budget of {args.budget:g} s spent")
        return
    row.update(q.run_child(cmd, prefix, args.peer_timeout, cwd=d))
    if row["status"] == "ok":
        with open(prefix + ".seconds") as fs:
            row["process_wall"], row["wall"] = row["wall"], float(fs.read())


def finish_domain(args, dom):
    """Inspects the domain's meshes (ours, then every peer mesh written)."""
    meshes = dom.pop("meshes") + [(row, prefix + ".node") for row, _, prefix, _ in dom.pop("jobs")
                                  if row.get("status") == "ok"]
    d = os.path.dirname(dom["vol"])
    dom["reference_betti"] = inspect(args, d, dom.pop("vol"), dom.pop("bounds"), meshes)
    return dom


def inspect(args, d, vol, b, meshes):
    """Runs the checker on all meshes at once; fills each row; returns the reference Betti
    numbers. A mesh the checker cannot read is marked `unreadable` (inspected one by one)."""
    ref = None
    groups = [meshes]
    while groups:
        group = groups.pop()
        js = os.path.join(d, "inspect.json")
        cmd = [args.bin, "--inspect", *[m for _, m in group], "--volume", vol, *b, "--json", js]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            if len(group) > 1:
                groups += [[m] for m in group]
            else:
                group[0][0].update(status="unreadable", detail=(p.stderr or p.stdout).strip()[:300])
            continue
        with open(js) as fj:
            for (row, _), i in zip(group, json.load(fj)):
                dih = i.get("dihedral") or {}
                level = i.get("level") or {}
                row.update(tets=i["tets"], nodes=i["nodes"], min=dih.get("min"), max=dih.get("max"),
                           valid=i["valid"], problems=[f"{p['kind']}: {p['count']}" for p in i["problems"]],
                           betti=i["betti"], reference_betti=i["reference_betti"],
                           matches_reference=i["matches_reference"], volume_error=i.get("volume_error"),
                           level_max_distance=level.get("max_distance"), level=level or None,
                           histogram=i["quality"]["histogram"])
                ref = i["reference_betti"]
    return ref


# ----------------------------------------------------------------------------

def fmt(x, spec):
    return "-" if x is None else format(x, spec)


def table(payload):
    lines = [f"{'domain':<12} {'tool':<16} {'surface':<7} {'status':<9} {'time s':>7} {'tets':>8} "
             f"{'min°':>6} {'max°':>6} {'valid':<5} {'betti':<10} {'ref':<10} ok"]
    for dom in payload["domains"]:
        for r in dom["rows"]:
            betti = "-" if r.get("betti") is None else ",".join(map(str, r["betti"]))
            ref = "-" if dom["reference_betti"] is None else ",".join(map(str, dom["reference_betti"]))
            ok = {True: "yes", False: "NO", None: "-"}[r.get("matches_reference")]
            lines.append(f"{dom['name']:<12} {r['tool']:<16} {r['surface']:<7} {r['status']:<9} "
                         f"{r.get('wall', 0.0):7.2f} {fmt(r.get('tets'), 'd'):>8} {fmt(r.get('min'), '.2f'):>6} "
                         f"{fmt(r.get('max'), '.2f'):>6} {str(r.get('valid', '-')):<5} {betti:<10} {ref:<10} {ok}")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin")
    ap.add_argument("--out")
    ap.add_argument("--json")
    ap.add_argument("--domains", default=",".join(DOMAINS))
    ap.add_argument("--peer-timeout", type=float, default=20.0, help="per TetGen / fTetWild run (s)")
    ap.add_argument("--ours-timeout", type=float, default=60.0, help="per tptd-mesh run (s)")
    ap.add_argument("--budget", type=float, default=120.0,
                    help="peer runs that would start later than this (s from the start) are skipped")
    ap.add_argument("--jobs", type=int, default=2, help="runs at a time (default 2)")
    ap.add_argument("--worker", nargs=4, metavar=("KIND", "IN", "PREFIX", "PARAM"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        return worker(*args.worker)
    if not (args.bin and args.out and args.json):
        ap.error("--bin, --out and --json are required")
    t0 = time.perf_counter()
    names = args.domains.split(",")
    with ThreadPoolExecutor(args.jobs) as pool:
        # ours first (cheap, and their meshes give the surfaces), then every peer run, then the
        # checker per domain
        domains = list(pool.map(lambda n: run_domain(args, n, t0), names))
        print(f"[compare_peers] ours on {len(names)} domains: {time.perf_counter() - t0:.1f} s", flush=True)
        jobs = [job for dom in domains for job in dom["jobs"]]
        list(pool.map(lambda job: run_peer(args, job, t0), jobs))
        print(f"[compare_peers] {len(jobs)} peer runs: {time.perf_counter() - t0:.1f} s", flush=True)
        domains = list(pool.map(lambda dom: finish_domain(args, dom), domains))
    payload = {"domains": domains, "peer_timeout": args.peer_timeout, "budget": args.budget,
               "ftetwild_edge": FTETWILD_EDGE, "ftetwild_epsilon": FTETWILD_EPSILON,
               "total_seconds": time.perf_counter() - t0,
               "loadavg": os.getloadavg()}
    with open(args.json, "w") as fj:
        json.dump(payload, fj, indent=1)
    print(table(payload))
    print(f"[compare_peers] total {payload['total_seconds']:.1f} s, load {payload['loadavg'][0]:.2f}")


if __name__ == "__main__":
    sys.exit(main())
