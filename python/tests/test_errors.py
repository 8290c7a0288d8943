"""Bad arguments and bad input raise ValueError with tptd-mesh's one-line message (flags
spelt as the Python parameters); a file the system refuses raises OSError."""

import numpy as np
import pytest

import tptd
from conftest import cli_error, py_names


def raises(exc, f, *args, **kwargs) -> str:
    with pytest.raises(exc) as e:
        f(*args, **kwargs)
    return str(e.value)


@pytest.mark.parametrize(
    "flags, kwargs",
    [
        (["--levels", "1,2,3", "--alpha", "1"], dict(levels=[1, 2, 3], alpha=1)),
        (["--alpha", "100", "--region-names", "a,b"], dict(alpha=100, region_names=["a", "b"])),
        (["--alpha", "100", "--quality", "--min-angle", "80"],
         dict(alpha=100, quality=True, min_angle=80)),
        (["--alpha", "100", "--quality", "--max-angle", "60"],
         dict(alpha=100, quality=True, max_angle=60)),
        (["--alpha", "100", "--spacing", "1,0,1"], dict(alpha=100, spacing=(1, 0, 1))),
        (["--alpha", "NaN"], dict(alpha=float("nan"))),
        (["--alpha", "100", "-j", "4096"], dict(alpha=100, threads=4096)),
        (["--levels", "1,3,2"], dict(levels=[1, 3, 2])),
        (["--levels", "1,2,3", "--region-names", "a,a"],
         dict(levels=[1, 2, 3], region_names=["a", "a"])),
        (["--resolution", "10", "--alpha", "1"], dict(resolution=10, alpha=1)),
    ],
)
def test_refusals_carry_the_cli_message(tmp_path, scan, flags, kwargs):
    cli = py_names(cli_error(tmp_path, "scan.npy", "-o", "x.vtu", *flags))
    py = raises(ValueError, tptd.mesh_file, tmp_path / "scan.npy", **kwargs)
    path = str(tmp_path / "scan.npy")
    assert py.replace(path, "scan.npy") == cli
    if "resolution" not in kwargs:
        on_array = raises(ValueError, tptd.mesh, scan, **kwargs)
        assert on_array.replace("volume: ", "scan.npy: ", 1) == cli


def test_the_interval_and_the_data(tmp_path, scan):
    for flags, kwargs in [([], {}), (["--alpha", "5", "--beta", "1"], dict(alpha=5, beta=1)),
                          (["--alpha", "1e9"], dict(alpha=1e9))]:
        cli = py_names(cli_error(tmp_path, "scan.npy", "-o", "x.vtu", *flags))
        assert cli.startswith("scan.npy: ")
        py = raises(ValueError, tptd.mesh, scan, **kwargs)
        assert py == "volume: " + cli.removeprefix("scan.npy: ")


def test_quality_options_need_quality(scan):
    assert raises(ValueError, tptd.mesh, scan, 100, min_angle=20) == (
        "min_angle applies only with quality")


def test_bad_method_and_threads(scan):
    assert "invalid value 'fast' for method" in raises(ValueError, tptd.mesh, scan, 1,
                                                        method="fast")
    assert "invalid value '0' for threads" in raises(ValueError, tptd.mesh, scan, 1, threads=0)


def test_bad_arrays(scan):
    assert "3-D" in raises(ValueError, tptd.mesh, scan[0], 1)
    assert "dtype" in raises(ValueError, tptd.mesh, scan.astype(complex), 1)
    assert "at least 2" in raises(ValueError, tptd.mesh, scan[:1], 1)
    bad = scan.astype(float)
    bad[1, 2, 3] = np.nan
    assert raises(ValueError, tptd.mesh, bad, 1).startswith("volume: value at grid vertex")


def test_missing_and_malformed_files(tmp_path):
    cli = cli_error(tmp_path, "missing.npy", "--alpha", "1", "-o", "x.vtu")
    py = raises(OSError, tptd.mesh_file, tmp_path / "missing.npy", 1)
    assert py.replace(str(tmp_path) + "/", "") == cli
    assert raises(OSError, tptd.read_volume, tmp_path / "missing.npy").replace(
        str(tmp_path) + "/", "") == cli
    (tmp_path / "bad.npy").write_bytes(b"\x93NUMPY garbage")
    cli = cli_error(tmp_path, "bad.npy", "--alpha", "1", "-o", "x.vtu")
    py = raises(ValueError, tptd.mesh_file, tmp_path / "bad.npy", 1)
    assert py.replace(str(tmp_path) + "/", "") == cli


def test_affine_excludes_spacing_and_origin(scan):
    for kwargs in [dict(spacing=(2, 1, 1)), dict(origin=(0, 0, 5))]:
        msg = raises(ValueError, tptd.mesh, scan, 100, affine=np.eye(4), **kwargs)
        assert msg == "affine excludes spacing and origin: give the affine or those two"


def test_a_run_that_would_not_fit_raises_memory_error(tmp_path, scan):
    for f, volume in ((tptd.mesh, scan), (tptd.mesh_file, tmp_path / "scan.npy")):
        message = raises(MemoryError, f, volume, 120.3, memory_limit=1000)
        assert "memory limit is 1000 B" in message and "\n" not in message
    assert "memory_limit" in raises(ValueError, tptd.mesh, scan, 120.3, memory_limit=0)
    # a limit the run fits in changes nothing
    fits = tptd.mesh(scan, 120.3, memory_limit=1 << 30)
    assert np.array_equal(fits.cells_dict["tetra"], tptd.mesh(scan, 120.3).cells_dict["tetra"])
