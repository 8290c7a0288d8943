#!/usr/bin/env python3
"""Monte Carlo volume of {alpha <= f <= beta} under trilinear interpolation of a .npy volume
(index units, spacing 1), to compare a mesh's volume with the trilinear truth.

  python3 benchmarks/trilinear_volume.py benchmarks/data/noisy_256.npy -2 2 2e8

Uniform points over the grid box (seed 1), f by scipy.ndimage.map_coordinates(order=1).
Prints the volume and its relative standard error.
"""
import argparse

import numpy as np
from scipy.ndimage import map_coordinates

BATCH = 5_000_000


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("volume", help=".npy file")
    ap.add_argument("alpha", type=float)
    ap.add_argument("beta", type=float)
    ap.add_argument("points", type=float, help="number of sample points, e.g. 2e8")
    a = ap.parse_args()
    d = np.load(a.volume).astype(np.float64)
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
