#!/usr/bin/env python3
"""Generate / locate the benchmark volumes for tptd-mesh.

Writes into benchmarks/data/ (git-ignored, never commit it):

  noisy_<N>.npy     float32 C-order (N, N, N): signed distance (in voxels) to a
                    union of spheres and tori plus band-limited Gaussian noise,
                    fixed seed.  The noise is strong enough at the cell scale
                    that the level sets near 0 are full of face and body
                    saddles of the trilinear interpolant.
  manifest.json     datasets, paths, shapes and the intervals to mesh.

The two MRI volumes are *not* copied: they are located inside the installed
PyPI package nilearn (nilearn/datasets/data/), nothing is downloaded.

  mni_t1   mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz   (uint8, 197x233x189)
           interval = grey-matter band picked from the intensity histogram
  mni_wm   mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz   (uint8 probability map)
           interval = [0.5 * max, +inf)

Usage:
  python3 benchmarks/make_data.py                 # 128^3 and 256^3 + MNI
  python3 benchmarks/make_data.py --sizes 128     # subset
  python3 benchmarks/make_data.py --quick         # 64^3 + MNI only (smoke test)
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "data")
SEED = 20240611

T1_NAME = "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz"
WM_NAME = "mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz"


# ----------------------------------------------------------------------------
# synthetic noisy distance fields
# ----------------------------------------------------------------------------

def band_limited_noise(n, corr_len, rng):
    """Unit-variance Gaussian random field, Gaussian spectrum with correlation
    length `corr_len` voxels, periodic (FFT), float32."""
    white = rng.standard_normal((n, n, n)).astype(np.float32)
    spec = np.fft.rfftn(white)
    del white
    k = np.fft.fftfreq(n).astype(np.float32)
    kr = np.fft.rfftfreq(n).astype(np.float32)
    # exp(-2 pi^2 s^2 |k|^2) is the transfer function of a Gaussian blur with std s
    s2 = np.float32(2.0 * math.pi ** 2 * corr_len ** 2)
    spec *= np.exp(-s2 * k[:, None, None] ** 2)
    spec *= np.exp(-s2 * k[None, :, None] ** 2)
    spec *= np.exp(-s2 * kr[None, None, :] ** 2)
    field = np.fft.irfftn(spec, s=(n, n, n), axes=(0, 1, 2)).astype(np.float32)
    del spec
    field -= field.mean()
    field /= field.std()
    return field


def noisy_distance_field(n, seed=SEED):
    """Signed distance (voxel units, negative inside) to a union of 4 spheres
    and 2 tori whose placement scales with n, plus noise:
      1.2 * noise(corr 3.0 vox) + 1.0 * noise(corr 0.5 vox).
    The coarse term wrinkles the surfaces (handles, tunnels, islands), the fine
    term puts ambiguous (saddle) faces into ~4% of the faces crossing a level
    set (a smooth field of this size has ~0)."""
    rng = np.random.default_rng(seed + n)
    c = (np.arange(n, dtype=np.float32) + 0.5) / n  # normalised cell-centre coords
    x = c[:, None, None]
    y = c[None, :, None]
    z = c[None, None, :]
    d = np.full((n, n, n), np.inf, dtype=np.float32)
    spheres = [((0.30, 0.32, 0.34), 0.17), ((0.70, 0.30, 0.62), 0.14),
               ((0.34, 0.72, 0.66), 0.13), ((0.68, 0.70, 0.30), 0.11)]
    for (cx, cy, cz), r in spheres:
        ds = np.sqrt((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) - r
        np.minimum(d, ds, out=d)
    tori = [((0.50, 0.50, 0.50), 0.27, 0.05, "z"), ((0.52, 0.48, 0.50), 0.22, 0.04, "x")]
    for (cx, cy, cz), big, small, axis in tori:
        dx, dy, dz = x - cx, y - cy, z - cz
        if axis == "z":
            q = np.sqrt(dx ** 2 + dy ** 2) - big
            dt = np.sqrt(q ** 2 + dz ** 2) - small
        else:
            q = np.sqrt(dy ** 2 + dz ** 2) - big
            dt = np.sqrt(q ** 2 + dx ** 2) - small
        np.minimum(d, dt, out=d)
    d *= np.float32(n)  # -> voxel units, so [-2, 2] is a ~4-voxel shell at any n
    d += np.float32(1.2) * band_limited_noise(n, 3.0, rng)
    d += np.float32(1.0) * band_limited_noise(n, 0.5, rng)
    return np.ascontiguousarray(d, dtype="<f4")


def ambiguous_face_stats(f, level):
    """(#ambiguous x-normal faces, #x-normal faces crossed by the level set):
    a face is ambiguous (has a saddle of the bilinear interpolant separating
    the level set) when its corner signs alternate diagonally."""
    s = f > level
    a, b, c, d = s[:, :-1, :-1], s[:, 1:, :-1], s[:, :-1, 1:], s[:, 1:, 1:]
    amb = int(((a == d) & (b == c) & (a != b)).sum())
    crossing = int(((a != b) | (a != c) | (a != d)).sum())
    return amb, crossing


# ----------------------------------------------------------------------------
# MNI volumes shipped with nilearn
# ----------------------------------------------------------------------------

def nilearn_data_dir():
    try:
        import nilearn
    except ImportError:
        return None
    d = os.path.join(os.path.dirname(nilearn.__file__), "datasets", "data")
    return d if os.path.isdir(d) else None


def safe_level(x):
    """A bound for integer data just above the grey level below x.

    Not an integer, so no vertex equals it, and not k + 0.5, the saddle of every checkerboard
    face with corners k, k+1 (real MRI has many): 0.0135 above an integer is not a simple
    fraction. tptd-mesh checks each bound against the critical values and face saddles near it
    and warns; it gives no warning for these bounds on the two MNI volumes.
    """
    return float(np.floor(x - 0.5)) + 0.0135


def t1_grey_matter_band(values):
    """Grey-matter band from the T1 intensity histogram.

    Smooth the histogram of the non-background voxels, take the two dominant
    modes (GM: lower, WM: upper, T1-weighted), and return
      alpha = left half-maximum of the GM mode,
      beta  = histogram minimum between the GM and WM modes.
    """
    v = np.asarray(values).ravel()
    hi = float(v.max())
    nb = 256
    hist, edges = np.histogram(v, bins=nb, range=(0.0, hi))
    centers = 0.5 * (edges[:-1] + edges[1:])
    hist[centers < 0.08 * hi] = 0  # background / air
    g = np.exp(-0.5 * (np.arange(-8, 9) / 2.5) ** 2)
    s = np.convolve(hist.astype(float), g / g.sum(), mode="same")
    peaks = [i for i in range(1, nb - 1) if s[i] >= s[i - 1] and s[i] > s[i + 1]]
    peaks.sort(key=lambda i: -s[i])
    p_main = peaks[0]
    p_other = next(p for p in peaks[1:] if abs(p - p_main) >= nb // 12)
    gm, wm = sorted((p_main, p_other))
    valley = gm + int(np.argmin(s[gm:wm + 1]))
    left = gm
    while left > 0 and s[left - 1] >= 0.5 * s[gm]:
        left -= 1
    alpha = safe_level(centers[left])
    beta = safe_level(centers[valley])
    return alpha, beta, {"gm_mode": float(centers[gm]), "wm_mode": float(centers[wm]),
                         "valley": float(centers[valley])}


# ----------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="128,256", help="comma-separated cube sizes (default 128,256)")
    ap.add_argument("--quick", action="store_true", help="only 64^3 + the MNI volumes")
    ap.add_argument("--force", action="store_true", help="regenerate even if the file exists")
    args = ap.parse_args()
    sizes = [64] if args.quick else [int(s) for s in args.sizes.split(",") if s.strip()]

    os.makedirs(DATA, exist_ok=True)
    man_path = os.path.join(DATA, "manifest.json")
    manifest = {"seed": SEED, "datasets": {}}
    if os.path.exists(man_path):
        try:
            with open(man_path) as f:
                manifest = json.load(f)
        except Exception:
            pass
    ds = manifest.setdefault("datasets", {})

    for n in sizes:
        name = f"noisy_{n}"
        path = os.path.join(DATA, name + ".npy")
        if args.force or not os.path.exists(path):
            t0 = time.perf_counter()
            f = noisy_distance_field(n)
            np.save(path, f)
            print(f"[make_data] {name}: {f.shape} float32 range [{f.min():.2f}, {f.max():.2f}] "
                  f"frac(f<=0)={np.mean(f <= 0):.3f} frac(|f|<=2)={np.mean(np.abs(f) <= 2):.3f} "
                  f"({time.perf_counter() - t0:.1f}s) -> {path}")
            for lvl in (-2.0, 0.0, 2.0):
                amb, cr = ambiguous_face_stats(f, lvl)
                print(f"[make_data]   level {lvl:+.0f}: {amb} ambiguous x-faces of {cr} crossed "
                      f"({100.0 * amb / max(cr, 1):.1f}%)")
        else:
            print(f"[make_data] {name}: exists, keeping {path} (use --force to regenerate)")
        ds[name] = {"kind": "noisy", "path": path, "shape": [n, n, n], "dtype": "float32",
                    "voxels": n ** 3,
                    "intervals": [[-2.0, 2.0], [None, 0.0]],
                    "note": "signed distance (voxels) to 4 spheres + 2 tori, + band-limited noise, seed %d" % SEED}

    nd = nilearn_data_dir()
    if nd is None:
        print("[make_data] WARNING: nilearn not importable; MNI volumes skipped (pip install nilearn)")
    else:
        import nibabel as nib
        t1 = os.path.join(nd, T1_NAME)
        wm = os.path.join(nd, WM_NAME)
        if os.path.exists(t1):
            img = nib.load(t1)
            a = np.asarray(img.dataobj)
            alpha, beta, info = t1_grey_matter_band(a)
            ds["mni_t1"] = {"kind": "mri", "path": t1, "shape": list(a.shape), "dtype": str(a.dtype),
                            "voxels": int(a.size), "intervals": [[alpha, beta]],
                            "note": "MNI ICBM152 2009a T1; grey-matter band: left half-max of GM mode "
                                    "to GM/WM histogram valley (%s)" % json.dumps(info)}
            print(f"[make_data] mni_t1: {a.shape} {a.dtype} GM band [{alpha}, {beta}] {info} <- {t1}")
        else:
            print(f"[make_data] WARNING: {t1} not found")
        if os.path.exists(wm):
            img = nib.load(wm)
            a = np.asarray(img.dataobj)
            lo = safe_level(0.5 * float(a.max()))
            ds["mni_wm"] = {"kind": "mri", "path": wm, "shape": list(a.shape), "dtype": str(a.dtype),
                            "voxels": int(a.size), "intervals": [[lo, None]],
                            "note": "MNI ICBM152 2009a white-matter probability map; [half the maximum, inf)"}
            print(f"[make_data] mni_wm: {a.shape} {a.dtype} interval [{lo}, inf) <- {wm}")
        else:
            print(f"[make_data] WARNING: {wm} not found")

    with open(man_path, "w") as f:
        json.dump(manifest, f, indent=2)
    print(f"[make_data] manifest -> {man_path}")


if __name__ == "__main__":
    sys.exit(main())
