"""tptd.inspect gives the JSON object of tptd-mesh --inspect --json for the same mesh (a file
or a meshio.Mesh) and volume (a file or an array); refusals carry the command line's
message."""

import json

import meshio
import numpy as np
import pytest

import tptd
from conftest import cli_error, py_names, run_cli

INTERVAL = ["--alpha", 120.3, "--beta", 180.7]


def cli_inspect(tmp_path, mesh, *args) -> dict:
    r = run_cli("--inspect", mesh, *args, "--json", "inspect.json", "-q", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    [out] = json.loads((tmp_path / "inspect.json").read_text())
    return out


def without_file(d: dict) -> dict:
    return {k: v for k, v in d.items() if k != "file"}


@pytest.fixture
def ring_msh(tmp_path, scan):
    r = run_cli("scan.npy", *INTERVAL, "-o", "ring.msh", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    return tmp_path / "ring.msh"


def test_a_file_as_the_cli(tmp_path, ring_msh):
    cli = cli_inspect(tmp_path, "ring.msh")
    py = tptd.inspect(ring_msh)
    assert py["file"] == str(ring_msh) and cli["file"] == "ring.msh"
    assert without_file(py) == without_file(cli)
    assert py["valid"] and py["tets"] > 0


def test_a_file_against_a_volume_file_and_array(tmp_path, scan, ring_msh):
    cli = cli_inspect(tmp_path, "ring.msh", "--volume", "scan.npy", *INTERVAL)
    assert cli["matches_reference"] is True and cli["labels"]["source"] == "file"
    py = tptd.inspect(ring_msh, tmp_path / "scan.npy", alpha=120.3, beta=180.7)
    assert without_file(py) == without_file(cli)
    on_array = tptd.inspect(ring_msh, scan, alpha=120.3, beta=180.7)
    assert without_file(on_array) == without_file(cli)
    # a mesh of the volume with its spacing
    tptd.write(tptd.mesh(scan, 120.3, 180.7, spacing=(1, 1, 2)), tmp_path / "spaced.msh")
    spaced = cli_inspect(tmp_path, "spaced.msh", "--volume", "scan.npy", *INTERVAL,
                         "--spacing", "1,1,2")
    assert spaced["valid"] is True
    py = tptd.inspect(tmp_path / "spaced.msh", scan, alpha=120.3, beta=180.7, spacing=(1, 1, 2))
    assert without_file(py) == without_file(spaced)


def test_a_meshio_mesh_as_its_file(tmp_path, scan, ring_msh):
    # the mesh meshio reads from the file: the same points, tets and labelled triangles
    m = meshio.read(ring_msh)
    cli = cli_inspect(tmp_path, "ring.msh", "--volume", "scan.npy", *INTERVAL)
    py = tptd.inspect(m, scan, alpha=120.3, beta=180.7)
    assert py["file"] == "mesh"
    assert without_file(py) == without_file(cli)
    # the mesh of tptd.mesh: the same as its .msh (the triangles in another order)
    direct = tptd.inspect(tptd.mesh(scan, 120.3, 180.7), scan, alpha=120.3, beta=180.7)
    for key in ("nodes", "tets", "boundary_faces", "valid", "betti", "labels", "flipped",
                "reference_betti", "matches_reference", "dihedral", "quality"):
        assert direct[key] == cli[key], key
    assert direct["volume"] == pytest.approx(cli["volume"], rel=1e-12)


def test_an_unlabelled_and_a_flipped_mesh(tmp_path, scan, ring_msh):
    m = meshio.read(ring_msh)
    bare = meshio.Mesh(m.points, [("tetra", m.cells_dict["tetra"])])
    meshio.write(tmp_path / "bare.vtu", bare)
    cli = cli_inspect(tmp_path, "bare.vtu", "--volume", "scan.npy", *INTERVAL)
    py = tptd.inspect(bare, scan, alpha=120.3, beta=180.7)
    assert cli["labels"]["source"] == "nearest_level"
    assert without_file(py) == without_file(cli)
    flipped = meshio.Mesh(m.points, [("tetra", m.cells_dict["tetra"][:, [0, 2, 1, 3]])])
    assert tptd.inspect(flipped)["flipped"] is True


@pytest.mark.parametrize(
    "flags, kwargs",
    [
        (["--alpha", "1"], dict(alpha=1)),
        (["--spacing", "1,1,2"], dict(spacing=(1, 1, 2))),
        (["--volume", "scan.npy"], dict(volume="scan.npy")),
        (["--volume", "scan.npy", "--alpha", "5", "--beta", "1"],
         dict(volume="scan.npy", alpha=5, beta=1)),
        (["--volume", "scan.npy", "--alpha", "1", "-j", "0"],
         dict(volume="scan.npy", alpha=1, threads=0)),
    ],
)
def test_refusals_carry_the_cli_message(tmp_path, scan, ring_msh, flags, kwargs):
    cli = py_names(cli_error(tmp_path, "--inspect", "ring.msh", *flags))
    if "volume" in kwargs:
        kwargs["volume"] = tmp_path / kwargs["volume"]
    with pytest.raises(ValueError) as e:
        tptd.inspect(ring_msh, **kwargs)
    msg = str(e.value).replace(str(tmp_path) + "/", "")
    if "-j" in flags:  # clap's own message: the value and the parameter only
        assert msg.startswith("invalid value '0' for threads")
        return
    assert msg == cli


def test_missing_and_malformed_files(tmp_path, scan, ring_msh):
    cli = cli_error(tmp_path, "--inspect", "missing.msh")
    with pytest.raises(OSError) as e:
        tptd.inspect(tmp_path / "missing.msh")
    assert str(e.value).replace(str(tmp_path) + "/", "") == cli
    (tmp_path / "bad.msh").write_text("$MeshFormat\ngarbage\n")
    cli = cli_error(tmp_path, "--inspect", "bad.msh")
    with pytest.raises(ValueError) as e:
        tptd.inspect(tmp_path / "bad.msh")
    assert str(e.value).replace(str(tmp_path) + "/", "") == cli
    cli = cli_error(tmp_path, "--inspect", "ring.msh", "--volume", "missing.npy", "--alpha", 1)
    with pytest.raises(OSError) as e:
        tptd.inspect(ring_msh, tmp_path / "missing.npy", alpha=1)
    assert str(e.value).replace(str(tmp_path) + "/", "") == cli


def test_bad_arrays(scan, ring_msh):
    with pytest.raises(ValueError, match="3-D"):
        tptd.inspect(ring_msh, scan[0], alpha=1)
    with pytest.raises(ValueError, match="no tetra cells"):
        tptd.inspect(meshio.Mesh(np.zeros((3, 3)), [("triangle", np.array([[0, 1, 2]]))]))
    with pytest.raises(ValueError, match="origin and affine apply only to an array volume"):
        tptd.inspect(ring_msh, "scan.npy", alpha=1, origin=(1, 0, 0))
