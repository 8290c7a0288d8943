#!/usr/bin/env python3
"""Graded meshes against peers at a given element size: `tptd-mesh --quality --max-edge H`
against TetGen, fTetWild and CGAL Mesh_3 asked for the same size, every mesh judged by our
checker. One command writes benchmarks/grade_peers_results.md:

  python3 benchmarks/grade_peers.py                  # about 15 min on 2 shared cores
  python3 benchmarks/grade_peers.py --size 48 --mni-crop 32 --max-edge 8 --out /tmp/g

Domains: a ball (sphere distance, radius 0.35 N), a solid torus (R = 0.28 N, r = 0.11 N) at
--size (default 64^3, levels off grid values as in tests/py/compare_peers.py) and a --mni-crop
(default 40^3) central crop of the nilearn MNI152 white matter at {f >= 127.0135}.

Tools, each a child process under --peer-timeout (a failure is a row, never an exception):
  tptd     `tptd-mesh VOL BOUNDS --quality --max-edge H -o ours.msh -j 1` (process wall)
  TetGen   PyPI `tetgen`, switches `pq1.2a<V>` with V = H^3 / (6 sqrt 2), the volume of the
           regular tet of edge H, on the boundary of our mesh (tests/py/compare_peers.py's worker)
  fTetWild PyPI `pytetwild`, `edge_length_abs=H` on the same surface (the same worker)
  CGAL     Debian python3-pygalmesh under /usr/bin/python3 (this script as --worker):
           `generate_from_array` on the label image of the interval with compare.py's facet
           criteria and `max_cell_circumradius = H sqrt(6) / 4` (the regular tet of edge H)
Times of the peers are the library call only. Every mesh goes through `tptd-mesh --inspect
MESH... --volume VOL BOUNDS --json J` (compare_peers.inspect): validity, Betti numbers against
the trilinear interval's, dihedral extremes; the mean edge length is computed here.
Meshes and logs go to --out (default benchmarks/out/grade_peers, git-ignored).
"""
import argparse
import json
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(REPO, "tests", "py"))

import quality as q          # noqa: E402  (domains, mesh I/O, child processes)
import compare_peers as cp   # noqa: E402  (levels, surface worker, checker)
import compare as cmp        # noqa: E402  (boundary of our mesh, machine line, CGAL settings)

RESULTS = os.path.join(HERE, "grade_peers_results.md")
OUT = os.path.join(HERE, "out", "grade_peers")
TOOLS = ["tptd --quality --max-edge", "TetGen -pq1.2a", "fTetWild", "CGAL Mesh_3"]


def dom_ball(n):
    f, _, note = q.dom_sphere(n)
    return f, None, cp.LEVEL, note


DOMAINS = {"ball": dom_ball, "torus": cp.dom_torus, "mni_wm": cp.dom_mni}


def cgal_worker(vol, prefix, alpha, beta, radius):
    """Under Debian's python3: CGAL Mesh_3 on the interval's label image, cells up to
    circumradius `radius`; writes prefix.node/.ele and prefix.seconds."""
    import pygalmesh
    f = np.load(vol)
    inside = np.ones(f.shape, dtype=bool)
    if alpha != "-":
        inside &= f >= float(alpha)
    if beta != "-":
        inside &= f <= float(beta)
    labels = np.ascontiguousarray(inside.astype(np.uint8))
    crit = dict(cmp.CGAL, max_cell_circumradius=float(radius))
    t0 = time.perf_counter()
    m = pygalmesh.generate_from_array(labels, (1.0, 1.0, 1.0), verbose=False, **crit)
    seconds = time.perf_counter() - t0
    T = np.concatenate([c.data for c in m.cells if c.type == "tetra"])
    cp.write_tetgen_files(prefix, np.asarray(m.points, dtype=np.float64), T)
    with open(prefix + ".seconds", "w") as fs:
        fs.write(repr(seconds))


def deep_mean_edge(P, T, vol, level, depth):
    """On a distance field `vol` (the ball's, the torus'): the mean edge length of the tets
    whose centroid lies deeper than `depth` below `level` (the field trilinear there)."""
    from scipy.ndimage import map_coordinates
    f = np.load(vol)
    c = P[T].mean(axis=1)
    deep = map_coordinates(f, c.T, order=1, mode="nearest") < level - depth
    if not deep.any():
        return None
    Q = P[T[deep]]
    pairs = [(a, b) for a in range(4) for b in range(a + 1, 4)]
    return float(np.mean([np.linalg.norm(Q[:, a] - Q[:, b], axis=1) for a, b in pairs]))


def measure(mesh, sdf=None):
    """Of a .msh or TetGen .node/.ele mesh: the mean length of its distinct edges, its number
    of components (tets joined through shared vertices) and the Euler characteristic of its
    boundary surface (2 (b0 - b1 + b2) for a manifold: the topology also where the checker
    gives no Betti numbers); with `sdf` = (volume, level, depth) of a distance field, the
    mean edge deeper than `depth` too."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    P, T = q.read_msh_tets(mesh) if mesh.endswith(".msh") else q.read_tetgen(mesh[:-5])
    E = np.concatenate([T[:, [a, b]] for a in range(4) for b in range(a + 1, 4)])
    E = np.unique(np.sort(E, axis=1), axis=0)
    used = np.unique(T)
    g = coo_matrix((np.ones(len(E)), (E[:, 0], E[:, 1])), shape=(len(P), len(P)))
    _, label = connected_components(g, directed=False)
    _, F = q.boundary_surface(T)
    fe = np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1), axis=0)
    return {"mean_edge": float(np.linalg.norm(P[E[:, 0]] - P[E[:, 1]], axis=1).mean()),
            "deep_mean_edge": deep_mean_edge(P, T, *sdf) if sdf else None,
            "components": int(len(np.unique(label[used]))),
            "boundary_euler": int(F.max() + 1 - len(fe) + len(F))}


def run_tool(args, row, cmd, prefix, mesh):
    """One child process; fills row (status, wall: the library call's seconds if written)."""
    for old in (prefix + ".seconds", mesh):
        if os.path.exists(old):
            os.remove(old)
    # in the mesh's folder: fTetWild drops __tracked_surface.stl in its working directory
    cwd = os.path.dirname(prefix)
    row.update(command=" ".join(cmd), **q.run_child(cmd, prefix, args.peer_timeout, cwd=cwd))
    if row["status"] == "ok" and os.path.exists(prefix + ".seconds"):
        with open(prefix + ".seconds") as fs:
            row["wall"] = float(fs.read())
    print(f"[grade_peers] {row['tool']}: {row['status']} {row['wall']:.1f} s", flush=True)
    return row["status"] == "ok"


def run_domain(args, name):
    f, alpha, beta, note = DOMAINS[name](args.mni_crop if name == "mni_wm" else args.size)
    d = os.path.join(args.out, name)
    os.makedirs(d, exist_ok=True)
    vol = os.path.join(d, "vol.npy")
    np.save(vol, np.ascontiguousarray(f))
    b = cp.bounds_args(alpha, beta)
    h = args.max_edge
    dom = {"name": name, "note": note, "shape": list(f.shape), "bounds": b, "rows": []}
    meshes = []

    def tool(label, cmd, prefix, mesh):
        row = {"tool": label}
        dom["rows"].append(row)
        if run_tool(args, row, cmd, prefix, mesh):
            meshes.append((row, mesh))

    ours = os.path.join(d, "ours.msh")
    tool(TOOLS[0], [args.bin, vol, *b, "--quality", "--max-edge", repr(h), "-o", ours,
                    "--msh-version", "4.1-binary", "-j", "1", "-q"], ours[:-4], ours)
    if meshes:
        V, F = cmp.boundary_from_file(ours)
        npz = os.path.join(d, "surf.npz")
        np.savez(npz, V=V, F=F, holes=q.cavity_hole_points(V, F, local=True)[0])
        worker = os.path.join(REPO, "tests", "py", "compare_peers.py")
        switches = f"pq1.2a{h ** 3 / (6 * np.sqrt(2)):.4g}"
        tg, fw = os.path.join(d, "tetgen"), os.path.join(d, "ftetwild")
        tool(TOOLS[1], [sys.executable, worker, "--worker", "tetgen", npz, tg, switches], tg, tg + ".node")
        tool(TOOLS[2], [sys.executable, worker, "--worker", "ftetwild", npz, fw, repr(h)], fw, fw + ".node")
    cg = os.path.join(d, "cgal")
    radius = float(h * np.sqrt(6) / 4)
    tool(TOOLS[3], [cmp.DEBIAN_PYTHON, os.path.abspath(__file__), "--worker", "cgal", vol, cg,
                    "-" if alpha is None else repr(alpha), "-" if beta is None else repr(beta),
                    repr(radius)], cg, cg + ".node")
    if meshes:
        dom["reference_betti"] = cp.inspect(args, d, vol, b, meshes)
        sdf = (vol, beta, 2 * h) if name in ("ball", "torus") else None
        dom["deep_from"] = 2 * h
        for row, mesh in meshes:
            row.update(measure(mesh, sdf))
    for r in dom["rows"]:
        r.pop("histogram", None)
        r.pop("level", None)
    return dom


def fmt(x, spec):
    return "–" if x is None else format(x, spec)


def table(dom):
    ref = dom.get("reference_betti")
    lines = [f"### {dom['name']}: {dom['note']}, `{' '.join(dom['bounds'])}`", "",
             f"Reference Betti numbers (trilinear interval): {ref}", "",
             "| tool | status | tets | mean edge | deep mean edge | min ° | max ° | valid | Betti | "
             "components, χ(∂) | time (s) |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in dom["rows"]:
        betti = r.get("betti")
        mark = "" if betti is None or betti == ref else " ✗"
        status = r["status"] if r["status"] == "ok" else f"{r['status']}: {r.get('detail', '')[:80]}"
        valid = r.get("valid", "–")
        if valid is False:
            valid = "no: " + "; ".join(r.get("problems", []))[:90]
        lines.append(f"| {r['tool']} | {status} | {fmt(r.get('tets'), ',')} | {fmt(r.get('mean_edge'), '.2f')} | "
                     f"{fmt(r.get('deep_mean_edge'), '.2f')} | "
                     f"{fmt(r.get('min'), '.2f')} | {fmt(r.get('max'), '.2f')} | {valid} | "
                     f"{betti}{mark} | {fmt(r.get('components'), 'd')}, {fmt(r.get('boundary_euler'), 'd')} | "
                     f"{r['wall']:.1f} |")
    return "\n".join(lines)


def render(payload):
    m = payload["machine"]
    out = ["# Graded meshes against peers at one element size", "",
           f"Command: `{payload['command']}` ({payload['total_seconds']:.0f} s).", "",
           f"Machine: {m['cpu']}, {m['nproc']} cores, {m['mem_total']}, {m['uname']}, shared with builds; "
           f"{m['date']}, tptd {m['tptd_mesh']} at {m['git_head']}; tetgen (PyPI) {m['tetgen']}, "
           f"pytetwild {m['pytetwild']}, pygalmesh {m['pygalmesh']} (Debian {m['python3_pygalmesh']}).", "",
           f"Size asked for: H = {payload['max_edge']:g} voxels (TetGen `-a` the regular tet of edge H, "
           "fTetWild `edge_length_abs = H`, CGAL `max_cell_circumradius` the regular tet's of edge H). "
           "Mean edge: over the distinct edges of the whole mesh (the boundary's included); deep mean "
           "edge: over the edges of the tets whose centroid lies more than 2H inside (the ball and "
           "the torus are distance fields), tet by tet. "
           "Betti numbers of the whole mesh by our checker; ✗ where they differ from the trilinear "
           "interval's. Times: ours the process (reading, meshing, quality pass, writing), the peers' "
           "the library call on our boundary surface (TetGen, fTetWild) or on the label image (CGAL).", ""]
    for dom in payload["domains"]:
        out += [table(dom), ""]
    return "\n".join(out)


def parse_args():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=None, help="tptd-mesh (default: $CARGO_TARGET_DIR or target/release)")
    ap.add_argument("--size", type=int, default=64, help="grid of the ball and the torus (default 64)")
    ap.add_argument("--mni-crop", type=int, default=40, help="MNI white-matter crop (default 40)")
    ap.add_argument("--max-edge", type=float, default=4.0, help="H, voxels (default 4)")
    ap.add_argument("--domains", default="ball,torus,mni_wm", help="comma-separated subset")
    ap.add_argument("--peer-timeout", type=float, default=300.0, help="per run (s)")
    ap.add_argument("--out", default=OUT, help="meshes and logs (default benchmarks/out/grade_peers)")
    ap.add_argument("--results", default=RESULTS, help="the Markdown written")
    ap.add_argument("--render-only", action="store_true", help="rewrite --results from --out's results.json")
    ap.add_argument("--worker", nargs="+", help=argparse.SUPPRESS)
    return ap.parse_args()


def main():
    args = parse_args()
    if args.worker:
        kind, *rest = args.worker
        return {"cgal": cgal_worker}[kind](*rest)
    if args.render_only:
        with open(os.path.join(args.out, "results.json")) as fj:
            payload = json.load(fj)
        with open(args.results, "w") as fm:
            return fm.write(render(payload) + "\n") and None
    command = "python3 benchmarks/grade_peers.py" + "".join(f" {a}" for a in sys.argv[1:])
    args.bin = os.path.abspath(args.bin or cmp.default_bin())
    os.makedirs(args.out, exist_ok=True)
    t0 = time.perf_counter()
    doms = [run_domain(args, n) for n in args.domains.split(",")]
    payload = {"command": command, "machine": cmp.machine_info(args), "max_edge": args.max_edge,
               "total_seconds": time.perf_counter() - t0, "domains": doms}
    with open(os.path.join(args.out, "results.json"), "w") as fj:
        json.dump(payload, fj, indent=1, default=str)
    with open(args.results, "w") as fm:
        fm.write(render(payload) + "\n")
    print(f"[grade_peers] wrote {args.results} ({payload['total_seconds']:.0f} s)")


if __name__ == "__main__":
    sys.exit(main())
