"""Higher quality targets over many small domains: smallest dihedral angle and volume change.

  python3 benchmarks/stages_matrix.py BINARY [OTHER_BINARY] [--sizes 24,28,36,40]
                                      [--targets 20/150,25/145,30/140]

Runs `BINARY --quality --min-angle A --max-angle B` on the analytic domains of
`quality.py` (sphere, torus, genus-3 solid, thin shell, two balls, random field) at each
size N and target, and prints per run the smallest dihedral angle and the volume change
against the plain mesh of the same binary. With a second binary (e.g. an older build from a
`git worktree`), prints both side by side and counts on how many runs each one has the
higher minimum (by more than 0.01°) and the smaller volume change (by more than 0.01 %).
Domains are written to benchmarks/data/quality/ (git-ignored); about a minute per binary.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from quality import make_domain  # noqa: E402

DOMAINS = ["sphere", "torus", "genus3", "shell", "two_spheres", "random"]


def mesh(binary, dom, extra, tmp):
    """Runs `binary` on the domain with `extra` flags; returns its report."""
    lo, hi = dom["intervals"][0]
    rep = os.path.join(tmp, "r.json")
    cmd = [binary, dom["path"], "-q", "-o", os.path.join(tmp, "m.vtu"), "--report", rep]
    cmd += ["--alpha", repr(float(lo))] if lo is not None else []
    cmd += ["--beta", repr(float(hi))] if hi is not None else []
    subprocess.run(cmd + extra, check=True, stdout=subprocess.DEVNULL)
    with open(rep) as f:
        return json.load(f)


def runs(binary, sizes, targets, tmp):
    """{(domain, N, target): (smallest angle, volume change in %)} for one binary."""
    out = {}
    for n in sizes:
        for name in DOMAINS:
            dom = make_domain(name, n, 40)
            plain = mesh(binary, dom, [], tmp)["volume"]
            for t in targets:
                lo, hi = t.split("/")
                r = mesh(binary, dom, ["--quality", "--min-angle", lo, "--max-angle", hi], tmp)
                out[(name, n, t)] = (r["quality"]["after"]["min_dihedral"],
                                     100.0 * (r["volume"] / plain - 1.0))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("binaries", nargs="+", help="one or two tptd-mesh binaries")
    ap.add_argument("--sizes", default="24,28,36,40")
    ap.add_argument("--targets", default="20/150,25/145,30/140")
    args = ap.parse_args()
    if len(args.binaries) > 2:
        ap.error("at most two binaries")
    sizes = [int(s) for s in args.sizes.split(",")]
    targets = args.targets.split(",")
    with tempfile.TemporaryDirectory() as tmp:
        res = [runs(b, sizes, targets, tmp) for b in args.binaries]
    print("| domain | N | target | " + " | ".join(f"min, volume ({os.path.basename(os.path.dirname(b)) or b})"
                                                  for b in args.binaries) + " |")
    print("|---|---|---|" + "---|" * len(res))
    for key in res[0]:
        cells = " | ".join(f"{r[key][0]:.2f}°, {r[key][1]:+.2f} %" for r in res)
        print(f"| {key[0]} | {key[1]} | {key[2]} | {cells} |")
    for t in targets:
        for i, r in enumerate(res):
            rows = [v for k, v in r.items() if k[2] == t]
            print(f"{t} binary {i + 1}: mean minimum {sum(v[0] for v in rows) / len(rows):.2f}°, "
                  f"lowest {min(v[0] for v in rows):.2f}°, largest volume change "
                  f"{max(abs(v[1]) for v in rows):.2f} %, over 0.5 %: {sum(abs(v[1]) > 0.5 for v in rows)} "
                  f"of {len(rows)}")
    if len(res) == 2:
        a, b = res
        higher = [sum(b[k][0] > a[k][0] + 0.01 for k in a), sum(a[k][0] > b[k][0] + 0.01 for k in a)]
        closer = [sum(abs(b[k][1]) < abs(a[k][1]) - 0.01 for k in a),
                  sum(abs(a[k][1]) < abs(b[k][1]) - 0.01 for k in a)]
        n = len(a)
        print(f"higher minimum: binary 2 on {higher[0]}, binary 1 on {higher[1]}, equal on "
              f"{n - sum(higher)} of {n} runs")
        print(f"smaller volume change: binary 2 on {closer[0]}, binary 1 on {closer[1]}, equal on "
              f"{n - sum(closer)} of {n} runs")


if __name__ == "__main__":
    main()
