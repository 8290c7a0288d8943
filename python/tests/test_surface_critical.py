"""tptd.isosurface gives the surface tptd-mesh writes for --alpha LEVEL -o OUT.ply/.obj,
array for array; tptd.critical_points the records of tptd-mesh --critical --json; refusals
carry the command line's message."""

import json

import meshio
import numpy as np
import pytest

import tptd
from conftest import cli_error, py_names, run_cli


def cli_surface(tmp_path, name, *args) -> meshio.Mesh:
    r = run_cli("scan.npy", *args, "-o", name, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    return meshio.read(tmp_path / name)


@pytest.mark.parametrize("name", ["s.ply", "s.obj"])
@pytest.mark.parametrize("caps", [False, True])
def test_isosurface_as_the_cli(tmp_path, scan, name, caps):
    cli = cli_surface(tmp_path, name, "--alpha", 120.3, *(["--caps"] if caps else []))
    py = tptd.isosurface(scan, 120.3, caps=caps)
    assert py.points.dtype == np.float64 and py.cells[0].data.dtype == np.int64
    assert np.array_equal(py.points, cli.points)
    assert np.array_equal(py.cells_dict["triangle"], cli.cells_dict["triangle"])
    if name.endswith(".ply"):
        assert np.array_equal(py.point_data["f"], cli.point_data["value"])
    if not caps:
        assert np.allclose(py.point_data["f"], 120.3, rtol=0, atol=1e-9)


def test_isosurface_options_as_the_cli(tmp_path, scan):
    cli = cli_surface(tmp_path, "s.ply", "--alpha", 120.3, "--method", "tptd", "--spacing",
                      "0.5,1,2")
    py = tptd.isosurface(scan, 120.3, method="tptd", spacing=(0.5, 1, 2), threads=1)
    assert np.array_equal(py.points, cli.points)
    assert np.array_equal(py.cells_dict["triangle"], cli.cells_dict["triangle"])


def test_isosurface_warnings_and_refusals(tmp_path, scan):
    with pytest.warns(tptd.MeshWarning, match="volume: alpha 120 equals the value of|level"):
        tptd.isosurface(scan, 120)
    cli = py_names(cli_error(tmp_path, "scan.npy", "--alpha", "1e9", "-o", "s.obj"))
    with pytest.raises(ValueError) as e:
        tptd.isosurface(scan, 1e9)
    assert str(e.value) == "volume: " + cli.removeprefix("scan.npy: ")
    with pytest.raises(ValueError, match="invalid value 'NaN' for level"):
        tptd.isosurface(scan, float("nan"))
    with pytest.raises(ValueError, match="3-D"):
        tptd.isosurface(scan[0], 1)


def cli_critical(tmp_path, *args) -> list:
    r = run_cli("scan.npy", "--critical", "-q", "--json", "c.json", *args, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    return json.loads((tmp_path / "c.json").read_text())


@pytest.mark.parametrize(
    "flags, kwargs",
    [
        ([], {}),
        (["--persistence"], dict(persistence=True)),
        (["--kind", "face_saddle,region_maximum", "--min-value", "100"],
         dict(kind=["face_saddle", "region_maximum"], min_value=100)),
        (["--min-persistence", "20", "--max-value", "190"],
         dict(min_persistence=20, max_value=190)),
        (["--spacing", "0.5,1,2", "-j", "1"], dict(spacing=(0.5, 1, 2), threads=1)),
    ],
)
def test_critical_points_as_the_cli(tmp_path, scan, flags, kwargs):
    cli = cli_critical(tmp_path, *flags)
    assert cli, "no points to compare"
    assert tptd.critical_points(scan, **kwargs) == cli
    assert tptd.critical_points_file(tmp_path / "scan.npy", **kwargs) == cli


def test_critical_points_in_physical_coordinates(scan):
    def xs(points):
        return np.array([p["position"][0] for p in points])

    plain = tptd.critical_points(scan)
    moved = tptd.critical_points(scan, origin=(10, 0, 0))
    assert len(moved) == len(plain) and np.allclose(xs(plain) + 10, xs(moved))
    shift = np.eye(4)
    shift[0, 3] = 10
    assert tptd.critical_points(scan, affine=shift) == moved


@pytest.mark.parametrize(
    "flags, kwargs",
    [
        (["--kind", "peak"], dict(kind="peak")),
        (["--min-persistence", "-1"], dict(min_persistence=-1)),
        (["--spacing", "1,0,1"], dict(spacing=(1, 0, 1))),
    ],
)
def test_critical_refusals_carry_the_cli_message(tmp_path, scan, flags, kwargs):
    cli = py_names(cli_error(tmp_path, "scan.npy", "--critical", *flags))
    with pytest.raises(ValueError) as e:
        tptd.critical_points_file(tmp_path / "scan.npy", **kwargs)
    assert str(e.value).replace(str(tmp_path) + "/", "") == cli
    with pytest.raises(ValueError) as e:
        tptd.critical_points(scan, **kwargs)
    assert str(e.value).replace("volume: ", "scan.npy: ", 1) == cli


def test_critical_bad_input(tmp_path, scan):
    with pytest.raises(ValueError, match="3-D"):
        tptd.critical_points(scan[0])
    cli = cli_error(tmp_path, "missing.npy", "--critical")
    with pytest.raises(OSError) as e:
        tptd.critical_points_file(tmp_path / "missing.npy")
    assert str(e.value).replace(str(tmp_path) + "/", "") == cli
    with pytest.raises(ValueError, match="affine excludes spacing and origin"):
        tptd.critical_points(scan, affine=np.eye(4), spacing=(1, 1, 2))
