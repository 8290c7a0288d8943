#!/usr/bin/env python3
"""Monte Carlo volume of {alpha <= f <= beta} under trilinear interpolation of a .npy volume
(index units, spacing 1), to compare a mesh's volume with the trilinear truth.

  python3 benchmarks/trilinear_volume.py benchmarks/data/noisy_256.npy -2 2 2e8

Uniform points over the grid box (seed 1), f by scipy.ndimage.map_coordinates(order=1).
Prints the volume and its relative standard error.

For thin bands, where few of the points hit, `--quadrature M` computes it instead by quadrature
(`band_volume`, also imported by thin_intervals.py): cells whose eight corners all lie in the
interval count whole (a trilinear function stays between its corner values); in a cell that
the interval only cuts, f is linear along z on every vertical line, so the length of the line
inside the interval is exact, and is integrated over an M x M midpoint grid in (x, y). Prints
the volume and its change from M/2, an estimate of the quadrature error.

  python3 benchmarks/trilinear_volume.py benchmarks/data/thin/t1_crop64.npy 150.23 150.77 0 --quadrature 32
"""
import argparse

import numpy as np
from scipy.ndimage import map_coordinates

BATCH = 5_000_000


def band_volume(d, alpha, beta, m=32, chunk=2_000_000):
    """Volume of {alpha <= f <= beta} (None: unbounded) under trilinear interpolation of the
    3D array d (index units), by the quadrature described in the module docstring."""
    d = np.asarray(d, dtype=np.float64)
    lo = -np.inf if alpha is None else float(alpha)
    hi = np.inf if beta is None else float(beta)
    c = [d[i:d.shape[0] - 1 + i, j:d.shape[1] - 1 + j, k:d.shape[2] - 1 + k]
         for i in (0, 1) for j in (0, 1) for k in (0, 1)]  # index 4i + 2j + k
    cmin = np.minimum.reduce(c)
    cmax = np.maximum.reduce(c)
    whole = int(np.count_nonzero((cmin >= lo) & (cmax <= hi)))
    cut = (cmax >= lo) & (cmin <= hi) & ~((cmin >= lo) & (cmax <= hi))
    corners = np.stack([ci[cut] for ci in c], axis=1)  # (K, 8)
    t = (np.arange(m) + 0.5) / m
    x = np.repeat(t, m)[None, :]
    y = np.tile(t, m)[None, :]
    total = 0.0
    step = max(1, chunk // (m * m))
    for s0 in range(0, len(corners), step):
        v = corners[s0:s0 + step]
        col = lambda n: v[:, n:n + 1]  # noqa: E731
        # f(x, y, z) = a(x, y) + b(x, y) z, a the bilinear bottom face (k = 0), a + b the top
        a = (col(0) * (1 - x) * (1 - y) + col(4) * x * (1 - y)
             + col(2) * (1 - x) * y + col(6) * x * y)
        top = (col(1) * (1 - x) * (1 - y) + col(5) * x * (1 - y)
               + col(3) * (1 - x) * y + col(7) * x * y)
        b = top - a
        flat = b == 0
        with np.errstate(divide="ignore", invalid="ignore"):
            z1 = (lo - a) / b
            z2 = (hi - a) / b
        zl = np.clip(np.minimum(z1, z2), 0.0, 1.0)
        zh = np.clip(np.maximum(z1, z2), 0.0, 1.0)
        length = np.where(flat, ((a >= lo) & (a <= hi)).astype(np.float64), zh - zl)
        total += float(np.nan_to_num(length).sum()) / (m * m)
    return whole + total


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("volume", help=".npy file")
    ap.add_argument("alpha", type=float)
    ap.add_argument("beta", type=float)
    ap.add_argument("points", type=float, help="number of sample points, e.g. 2e8")
    ap.add_argument("--quadrature", type=int, metavar="M",
                    help="quadrature on M x M lines per cut cell instead of points (thin bands)")
    a = ap.parse_args()
    d = np.load(a.volume).astype(np.float64)
    if a.quadrature:
        v = band_volume(d, a.alpha, a.beta, a.quadrature)
        h = band_volume(d, a.alpha, a.beta, max(1, a.quadrature // 2))
        print(f"volume {v:.3f}  change from M/{2} {v - h:+.3f} ({(v - h) / v:+.2e})")
        return
    ext = np.array(d.shape) - 1
    rng = np.random.default_rng(1)
    hit = tot = 0
    for _ in range(max(1, int(a.points) // BATCH)):
        p = rng.random((3, BATCH)) * ext[:, None]
        f = map_coordinates(d, p, order=1)
        hit += np.count_nonzero((f >= a.alpha) & (f <= a.beta))
        tot += BATCH
    frac = hit / tot
    print(f"volume {np.prod(ext) * frac:.1f}  relative standard error {np.sqrt((1 - frac) / (tot * frac)):.2e}")


if __name__ == "__main__":
    main()
