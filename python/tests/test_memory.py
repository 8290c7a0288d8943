"""Input arrays are not copied: a Fortran-ordered array of a stored type is read in place
(the peak resident memory of a call grows by much less than the array), a C-ordered one is
copied once (the peak grows by the copy, which shows the measurement sees copies); the array
is not held after the call."""

import gc
import weakref

import numpy as np
import pytest

import tptd
from conftest import assert_same, assert_valid

CLEAR_REFS = "/proc/self/clear_refs"


def status(key: str) -> int:
    """A memory line of `/proc/self/status` (`VmRSS`, `VmHWM`) in bytes."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(key + ":"):
                return int(line.split()[1]) * 1024
    raise KeyError(key)


def reset_peak() -> bool:
    """Sets the peak resident memory (`VmHWM`) to the current one; False where Linux's
    `clear_refs` is unavailable or does not reset it."""
    try:
        with open(CLEAR_REFS, "w") as f:
            f.write("5")
        return status("VmHWM") - status("VmRSS") < 16 << 20
    except (OSError, KeyError):
        return False


def peak_growth(call) -> int:
    """Bytes by which the peak resident memory during `call()` exceeds the memory before."""
    gc.collect()
    if not reset_peak():
        pytest.skip("cannot reset the peak resident memory (/proc/self/clear_refs)")
    before = status("VmRSS")
    call()
    return status("VmHWM") - before


def squared_distance(n: int) -> np.ndarray:
    """`(i - c)² + (j - c)² + (k - c)²` on an n³ float64 grid, Fortran-ordered, built in
    place (no temporary the size of the volume)."""
    d = (np.arange(n) - (n - 1) / 2) ** 2
    a = np.empty((n, n, n), order="F")
    a[...] = d[:, None, None]
    a += d[None, :, None]
    a += d[None, None, :]
    return a


@pytest.fixture(scope="module")
def big():
    return squared_distance(300)  # 216 MB


def test_a_fortran_array_is_not_copied(big):
    assert big.flags.f_contiguous and big.nbytes == 216_000_000
    meshes = []
    grown = peak_growth(lambda: meshes.append(tptd.mesh(big, None, 30.1, analysis=False)))
    assert 0 < meshes[0].info["tets"] < 10_000, "a small ball, a tiny mesh"
    assert grown < 0.25 * big.nbytes, f"peak grew by {grown / 1e6:.0f} MB"


def test_a_c_ordered_array_is_copied_once(big):
    c = np.ascontiguousarray(big)
    assert c.flags.c_contiguous and not c.flags.f_contiguous
    meshes = []
    grown = peak_growth(lambda: meshes.append(tptd.mesh(c, None, 30.1, analysis=False)))
    assert grown > 0.9 * c.nbytes, f"peak grew by {grown / 1e6:.0f} MB only"
    assert grown < 1.5 * c.nbytes, f"peak grew by {grown / 1e6:.0f} MB: more than one copy"
    del c
    gc.collect()
    # the same mesh as in place
    assert_same(meshes[0], tptd.mesh(big, None, 30.1, analysis=False))


def test_in_place_arrays_of_every_stored_dtype_and_offset_views(scan):
    for dtype in ("uint8", "int16", "uint16", "float32", "float64"):
        img = scan.astype(dtype)
        c = tptd.mesh(img, 120.3)
        f = np.asfortranarray(img)
        # Fortran-contiguous, starting inside a larger buffer
        padded = np.asfortranarray(np.pad(img, ((0, 0), (0, 0), (2, 3))))[:, :, 2:-3]
        assert padded.flags.f_contiguous and not padded.flags.owndata
        for a in (f, padded):
            m = tptd.mesh(a, 120.3, check=True)
            assert_same(m, c)
            assert_valid(m)


def test_the_array_is_not_held_after_the_call(scan):
    for order, alpha in (("F", 120.3), ("C", 120.3), ("F", 1e6)):
        a = np.array(scan.astype(np.float32), order=order)
        ref = weakref.ref(a)
        if alpha > 1e5:  # an empty interval: the call fails
            with pytest.raises(ValueError):
                tptd.mesh(a, alpha)
        else:
            tptd.mesh(a, alpha)
        del a
        gc.collect()
        assert ref() is None, f"{order}-ordered array held (alpha {alpha})"


def test_a_read_only_array_is_read_in_place(scan):
    f = np.asfortranarray(scan)
    f.flags.writeable = False
    assert_same(tptd.mesh(f, 120.3), tptd.mesh(scan, 120.3))
