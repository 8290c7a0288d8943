"""tptd.write gives the bytes tptd-mesh writes for the same mesh, in every format and option,
through a temporary renamed when complete: a refused write leaves every file as it was."""

import os

import meshio
import numpy as np
import pytest

import tptd
from conftest import cli_error, py_names, run_cli

INTERVAL = ["--alpha", 120.3, "--beta", 180.7]
LEVELS = ["--levels", "60.3,120.3,180.7", "--region-names", "outer,inner"]


def cli_bytes(tmp_path, name, *args) -> bytes:
    r = run_cli("scan.npy", *args, "-o", name, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    return (tmp_path / name).read_bytes()


@pytest.mark.parametrize(
    "name, flags, kwargs",
    [
        ("x.msh", [], {}),
        ("x.msh", ["--msh-version", "2.2"], dict(msh_version="2.2")),
        ("x.msh", ["--msh-version", "4.1-binary"], dict(msh_version="4.1-binary")),
        ("x.inp", [], {}),
        ("x.vtu", [], {}),
        ("x.vtu", ["--vtu-encoding", "zlib"], dict(vtu_encoding="zlib")),
        ("x.obj", [], {}),
        ("x.ply", [], {}),
        ("x.stl", ["--ascii"], dict(ascii=True)),
    ],
)
def test_the_bytes_of_the_cli(tmp_path, scan, name, flags, kwargs):
    cli = cli_bytes(tmp_path, "cli-" + name, *INTERVAL, *flags)
    m = tptd.mesh(scan, 120.3, 180.7)
    tptd.write(m, tmp_path / name, **kwargs)
    assert (tmp_path / name).read_bytes() == cli
    if name.endswith((".msh", ".vtu")):
        back = meshio.read(tmp_path / name)
        assert np.array_equal(back.points, m.points)
        assert np.array_equal(back.cells_dict["tetra"], m.cells_dict["tetra"])


@pytest.mark.parametrize("name", ["r.msh", "r.inp", "r.vtu", "r.obj"])
def test_regions_as_the_cli(tmp_path, scan, name):
    cli = cli_bytes(tmp_path, "cli-" + name, *LEVELS)
    m = tptd.mesh(scan, levels=[60.3, 120.3, 180.7], region_names=["outer", "inner"])
    tptd.write(m, tmp_path / name)
    assert (tmp_path / name).read_bytes() == cli
    # without the report the levels and names come from the groups
    m.info = None
    tptd.write(m, tmp_path / ("again-" + name))
    assert (tmp_path / ("again-" + name)).read_bytes() == cli


def test_quality_mesh_as_the_cli(tmp_path, scan):
    cli = cli_bytes(tmp_path, "cli.msh", *INTERVAL, "--quality")
    tptd.write(tptd.mesh(scan, 120.3, 180.7, quality=True), tmp_path / "x.msh")
    assert (tmp_path / "x.msh").read_bytes() == cli


def listing(d):
    return sorted(os.listdir(d))


def test_refusals_carry_the_cli_message_and_write_nothing(tmp_path, scan):
    m = tptd.mesh(scan, 120.3, 180.7)
    before = listing(tmp_path)
    for name, flags, kwargs in [
        ("x.off", [], {}),
        ("x.vtu", ["--msh-version", "2.2"], dict(msh_version="2.2")),
        ("x.msh", ["--ascii"], dict(ascii=True)),
    ]:
        cli = py_names(cli_error(tmp_path, "scan.npy", *INTERVAL, *flags, "-o", name))
        with pytest.raises(ValueError) as e:
            tptd.write(m, tmp_path / name, **kwargs)
        assert str(e.value).replace(str(tmp_path) + "/", "") == cli
    with pytest.raises(ValueError, match="invalid value '3.0' for msh_version: possible values"):
        tptd.write(m, tmp_path / "x.msh", msh_version="3.0")
    assert listing(tmp_path) == before


def test_a_missing_folder_is_an_os_error(tmp_path, scan):
    m = tptd.mesh(scan, 120.3, 180.7)
    cli = cli_error(tmp_path, "scan.npy", *INTERVAL, "-o", "no/x.msh")
    with pytest.raises(OSError) as e:
        tptd.write(m, tmp_path / "no" / "x.msh")
    assert str(e.value).replace(str(tmp_path) + "/", "") == cli


def test_a_failed_write_keeps_the_old_file(tmp_path, scan):
    m = tptd.mesh(scan, 120.3, 180.7)
    target = tmp_path / "x.inp"
    target.write_bytes(b"old")
    before = listing(tmp_path)
    bad = meshio.Mesh(m.points, [("tetra", m.cells[0].data), ("triangle", m.cells[1].data[:5])],
                      point_data=m.point_data,
                      cell_data={"gmsh:physical": [m.cell_data["gmsh:physical"][0],
                                                   m.cell_data["gmsh:physical"][1][:5]]})
    bad.cells[1].data[0] = [0, 1, len(m.points) - 1]  # no face of any tetra
    with pytest.raises(ValueError, match="is not a face of any tetrahedron"):
        tptd.write(bad, target)
    assert target.read_bytes() == b"old"
    assert listing(tmp_path) == before


def test_bad_meshes(tmp_path, scan):
    m = tptd.mesh(scan, 120.3, 180.7)
    with pytest.raises(ValueError, match="no tetra cells"):
        tptd.write(meshio.Mesh(m.points, [("triangle", m.cells[1].data)]), tmp_path / "x.msh")
    with pytest.raises(ValueError, match=r"mesh: points must be an \(n, 3\) array"):
        tptd.write(meshio.Mesh(m.points[:, :2], [("tetra", m.cells[0].data)]), tmp_path / "x.msh")
    far = m.cells[0].data.copy()
    far[0, 0] = len(m.points)
    with pytest.raises(ValueError, match="node index"):
        tptd.write(meshio.Mesh(m.points, [("tetra", far)]), tmp_path / "x.msh")
    assert not (tmp_path / "x.msh").exists()
    # a bare mesh: tetrahedra and points, no field, no labels
    bare = meshio.Mesh(m.points, [("tetra", m.cells[0].data)])
    tptd.write(bare, tmp_path / "bare.vtu")
    back = meshio.read(tmp_path / "bare.vtu")
    assert np.array_equal(back.cells_dict["tetra"], m.cells[0].data)
    assert not np.ravel(back.point_data["f"]).any()
