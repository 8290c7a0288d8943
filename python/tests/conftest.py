"""Helpers of the tests: the `tptd-mesh` binary of this tree, its runs and messages, small
volumes, and the checks every mesh gets (positive tetrahedra, the library's checker)."""

import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import meshio
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def cli_path() -> str:
    """`$TPTD_MESH`, else the newest `tptd-mesh` built in this tree, else the one on PATH."""
    env = os.environ.get("TPTD_MESH")
    if env:
        return env
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    built = [target / p / "tptd-mesh" for p in ("debug", "release")]
    built = [p for p in built if p.is_file()]
    if built:
        return str(max(built, key=lambda p: p.stat().st_mtime))
    found = shutil.which("tptd-mesh")
    if found:
        return found
    raise RuntimeError("tptd-mesh not found: run `cargo build` or set TPTD_MESH")


def run_cli(*args, cwd):
    return subprocess.run(
        [cli_path(), *map(str, args)], capture_output=True, text=True, cwd=cwd
    )


def cli_mesh(tmp_path, *args):
    """Runs `tptd-mesh ARGS -o cli.vtu --report cli.json --check`: the mesh meshio reads
    and the report."""
    out, report = tmp_path / "cli.vtu", tmp_path / "cli.json"
    r = run_cli(*args, "-o", out, "--report", report, "--check", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "check     valid" in r.stdout, r.stdout
    return meshio.read(out), json.loads(report.read_text())


def cli_error(tmp_path, *args) -> str:
    """The one-line error of `tptd-mesh ARGS`, without its prefix and help hint."""
    r = run_cli(*args, cwd=tmp_path)
    assert r.returncode in (1, 2), r
    line = r.stderr.strip().splitlines()[-1]
    line = line.removeprefix("tptd-mesh: error: ")
    return line.removesuffix(" (see tptd-mesh --help)")


def py_names(message: str) -> str:
    """A command-line message with each flag spelt as the Python parameter."""
    flag = r"'?(--[a-z][a-z-]*|-j)(?: <[^>]*>)?'?"

    def name(m):
        f = m.group(1)
        return "threads" if f == "-j" else f[2:].replace("-", "_")

    return re.sub(flag, name, message)


def ring(shape=(32, 32, 28), dtype=np.uint8):
    """The README's image, smaller: a ring with a ball in its hole, indexed [i, j, k]."""
    c = (np.array(shape) - 1) / 2
    x, y, z = np.mgrid[: shape[0], : shape[1], : shape[2]] - c[:, None, None, None]
    r = min(shape) * 0.3
    ring = np.hypot(np.hypot(x, y) - r, z)
    ball = np.sqrt(x**2 + y**2 + z**2)
    img = 40 + 160 * np.exp(-((ring / 3.5) ** 2)) + 160 * np.exp(-((ball / 3.5) ** 2))
    return img.round().astype(dtype)


def tet_volumes(m: meshio.Mesh) -> np.ndarray:
    p = m.points[m.cells_dict["tetra"]]
    a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    return np.einsum("ij,ij->i", a, np.cross(b, c)) / 6


def assert_valid(m: meshio.Mesh, report=None):
    """Every tet positive; the total volume that of the report (the library's sum)."""
    v = tet_volumes(m)
    assert len(v) > 0 and (v > 0).all(), f"{(v <= 0).sum()} tets not positive"
    if report is not None:
        assert v.sum() == pytest.approx(report["volume"], rel=1e-9)
    return v.sum()


def assert_same(py: meshio.Mesh, cli: meshio.Mesh):
    """The same mesh: points, field and tetrahedra identical, and the regions if any."""
    assert np.array_equal(py.points, cli.points)
    assert np.array_equal(py.point_data["f"], np.ravel(cli.point_data["f"]))
    assert np.array_equal(py.cells_dict["tetra"], cli.cells_dict["tetra"])
    if "region" in cli.cell_data:
        cli_region = np.ravel(cli.cell_data["region"][0])
        assert np.array_equal(py.cell_data_dict["region"]["tetra"], cli_region)


@pytest.fixture
def scan(tmp_path):
    """The ring image as an array and as `scan.npy` (C order, uint8)."""
    img = ring()
    np.save(tmp_path / "scan.npy", img)
    return img
