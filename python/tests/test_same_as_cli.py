"""Python meshes equal tptd-mesh's for the same input: points, field, tets and regions
identical (arrays compared, not files), and the library's checker passes both."""

import meshio
import numpy as np
import pytest

import tptd
from conftest import assert_same, assert_valid, cli_mesh, ring, run_cli


def test_an_array_meshes_as_its_npy_file(tmp_path, scan):
    cli, report = cli_mesh(tmp_path, "scan.npy", "--alpha", 120.3, "--beta", 180.7)
    py = tptd.mesh(scan, 120.3, 180.7, check=True)
    assert_same(py, cli)
    assert py.info["tets"] == report["tets"] == len(py.cells_dict["tetra"])
    assert py.info["volume"] == report["volume"]
    assert py.info["betti"] == report["betti"]
    assert_valid(py, report)


def test_fortran_and_c_order_give_the_same_mesh(scan):
    c = tptd.mesh(scan, 120.3)
    f = tptd.mesh(np.asfortranarray(scan), 120.3)
    strided = tptd.mesh(np.ascontiguousarray(np.pad(scan, 1)[1:-1, 1:-1, 1:-1]), 120.3)
    view = tptd.mesh(np.pad(scan, ((0, 0), (0, 0), (0, 3)))[:, :, :-3], 120.3)
    for m in (f, strided, view):
        assert_same(m, c)
    assert_valid(c)


@pytest.mark.parametrize(
    "dtype",
    ["uint8", "int8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "float32",
     "float64"],
)
def test_every_dtype_as_the_cli(tmp_path, dtype):
    img = ring((14, 13, 12))
    img = (img // 2 if dtype == "int8" else img).astype(dtype)
    np.save(tmp_path / "v.npy", img)
    cli, report = cli_mesh(tmp_path, "v.npy", "--alpha", 90.3)
    py = tptd.mesh(img, 90.3, check=True)
    assert_same(py, cli)
    assert py.info["samples"] == report["samples"]
    assert_valid(py, report)


def test_big_endian_and_float16_arrays(scan):
    native = tptd.mesh(scan.astype("<f4"), 120.3)
    assert_same(tptd.mesh(scan.astype(">f4"), 120.3), native)
    assert_same(tptd.mesh(scan.astype(np.float16), 120.3), native)


def test_spacing_as_the_cli(tmp_path, scan):
    cli, report = cli_mesh(tmp_path, "scan.npy", "--alpha", 120.3, "--spacing", "0.5,1,2")
    py = tptd.mesh(scan, 120.3, spacing=(0.5, 1, 2), check=True)
    assert_same(py, cli)
    assert_valid(py, report)
    moved = tptd.mesh(scan, 120.3, spacing=(0.5, 1, 2), origin=(10, -5, 3))
    assert np.allclose(moved.points, py.points + [10, -5, 3], rtol=0, atol=1e-12)


def test_regions_as_the_cli_and_kept_in_vtu_and_msh(tmp_path, scan):
    levels = ["--levels", "60.3,120.3,180.7", "--region-names", "outer,inner"]
    cli, report = cli_mesh(tmp_path, "scan.npy", *levels)
    py = tptd.mesh(scan, levels=[60.3, 120.3, 180.7], region_names=["outer", "inner"],
                   check=True)
    assert_same(py, cli)
    regions = py.cell_data_dict["region"]["tetra"]
    py_tets = py.cells_dict["tetra"]
    assert set(regions) == {0, 1}
    assert [r["tets"] for r in py.info["regions"]] == [(regions == k).sum() for k in (0, 1)]
    assert py.info["regions"] == report["regions"]
    assert_valid(py, report)
    # a .vtu through meshio keeps the regions and the tags as cell data
    meshio.write(tmp_path / "py.vtu", py)
    vtu = meshio.read(tmp_path / "py.vtu")
    for key in ("region", "gmsh:physical", "gmsh:geometrical"):
        assert np.array_equal(vtu.cell_data_dict[key]["tetra"], py.cell_data_dict[key]["tetra"])
    # the mesh as returned, written as .msh 4.1 and 2.2 by tptd.write: meshio reads back a
    # volume group per region (physical tag region + 1) and a surface group per level, with
    # the tags of the CLI's own .msh
    msh = tmp_path / "cli.msh"
    assert run_cli("scan.npy", *levels, "-o", msh, cwd=tmp_path).returncode == 0
    ours = meshio.read(msh)
    names = {"outer", "inner", "level1", "level2", "level3"}
    for version in ("4.1", "2.2", "4.1-binary"):
        tptd.write(py, tmp_path / "py.msh", msh_version=version)
        back = meshio.read(tmp_path / "py.msh")
        assert names <= set(back.field_data)
        for name in names:
            assert back.field_data[name][0] == ours.field_data[name][0], (version, name)
        tets = back.cells_dict["tetra"]
        tags = back.cell_data_dict["gmsh:physical"]["tetra"]
        assert len(tets) == len(regions)
        assert np.array_equal(tags[by_vertices(tets)], regions[by_vertices(py_tets)] + 1)
        assert set(tags) == {back.field_data["outer"][0], back.field_data["inner"][0]}


def by_vertices(tets):
    """The order of `tets` by their sorted vertex numbers (the same tets listed in another
    order, e.g. grouped by region as a .msh file holds them, then line up)."""
    return np.lexsort(np.sort(tets, axis=1).T[::-1])


@pytest.mark.parametrize(
    "kwargs",
    [dict(alpha=120.3, beta=180.7),
     dict(levels=[60.3, 120.3, 180.7], region_names=["outer", "inner"])],
)
def test_converted_while_meshing_as_when_held(scan, kwargs):
    """Without the check the mesh goes to numpy slab by slab as it is made; with it the run
    holds the mesh and it is converted after: the same arrays, tags and groups."""
    streamed = tptd.mesh(scan, **kwargs)
    held = tptd.mesh(scan, check=True, **kwargs)
    assert held.info["timings_seconds"]["check"] is not None
    assert np.array_equal(streamed.points, held.points)
    assert np.array_equal(streamed.point_data["f"], held.point_data["f"])
    assert [c.type for c in streamed.cells] == [c.type for c in held.cells] == [
        "tetra", "triangle"]
    for a, b in zip(streamed.cells, held.cells):
        assert a.data.dtype == b.data.dtype == np.int64
        assert np.array_equal(a.data, b.data)
    assert streamed.cell_data.keys() == held.cell_data.keys()
    for key in held.cell_data:
        for a, b in zip(streamed.cell_data[key], held.cell_data[key]):
            assert a.dtype == b.dtype and np.array_equal(a, b), key
    assert streamed.field_data.keys() == held.field_data.keys()
    for name, v in held.field_data.items():
        assert np.array_equal(streamed.field_data[name], v), name


def test_boundary_triangles_are_the_labelled_faces(scan):
    m = tptd.mesh(scan, 120.3, 180.7)
    tris = m.cells_dict["triangle"]
    assert set(m.field_data) == {"alpha", "beta", "domain"}
    tags = m.cell_data_dict["gmsh:physical"]["triangle"]
    assert set(tags) == {m.field_data["alpha"][0], m.field_data["beta"][0]}
    counts = {k: v for k, v in m.info["boundary_triangles"].items() if v}
    assert counts == {"alpha": (tags == 1).sum(), "beta": (tags == 2).sum()}
    # every triangle is a face of exactly one tet (the boundary is closed)
    faces = np.sort(m.cells_dict["tetra"][:, [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]]],
                    axis=2).reshape(-1, 3)
    _, counts = np.unique(faces, axis=0, return_counts=True)
    assert (counts == 1).sum() == len(tris)
    assert len(tptd.mesh(scan, 120.3, 180.7, boundary=False).cells) == 1


def test_quality_as_the_cli(tmp_path, scan):
    cli, report = cli_mesh(tmp_path, "scan.npy", "--alpha", 120.3, "--beta", 180.7,
                           "--quality", "--min-angle", 20)
    py = tptd.mesh(scan, 120.3, 180.7, quality=True, min_angle=20, check=True)
    assert_same(py, cli)
    assert py.info["quality"]["after"] == report["quality"]["after"]
    assert_valid(py, report)


def test_graded_interior_as_the_cli(tmp_path, scan):
    cli, report = cli_mesh(tmp_path, "scan.npy", "--alpha", 60.3, "--max-edge", 4,
                           "--grading", 2)
    py = tptd.mesh(scan, 60.3, max_edge=4, grading=2, check=True)
    assert_same(py, cli)
    assert py.info["grade"] == {**report["grade"], "seconds": py.info["grade"]["seconds"]}
    assert py.info["grade"]["tets_after"] < py.info["grade"]["tets_before"]
    fine = tptd.mesh(scan, 60.3)
    assert py.info["betti"] == fine.info["betti"]
    assert len(py.cells_dict["tetra"]) < len(fine.cells_dict["tetra"])
    assert_valid(py, report)
    with pytest.raises(ValueError, match="max_edge 1.2 is less than 1.5 cells"):
        tptd.mesh(scan, 60.3, max_edge=1.2)
    with pytest.raises(ValueError, match="grading"):
        tptd.mesh(scan, 60.3, grading=2)


def test_mesh_file_and_read_volume_as_the_cli(tmp_path, scan):
    cli, report = cli_mesh(tmp_path, "scan.npy", "--alpha", 120.3, "--method", "tptd")
    py = tptd.mesh_file(tmp_path / "scan.npy", 120.3, method="tptd", check=True)
    assert_same(py, cli)
    assert_valid(py, report)
    array, affine = tptd.read_volume(tmp_path / "scan.npy")
    assert array.dtype == np.uint8 and np.array_equal(array, scan)
    assert array.flags.f_contiguous
    assert np.array_equal(affine, np.eye(4))
    assert_same(tptd.mesh(array, 120.3, method="tptd", affine=affine), cli)


def test_no_analysis_as_the_cli(tmp_path, scan):
    cli, report = cli_mesh(tmp_path, "scan.npy", "--alpha", 120.3, "--no-analysis")
    py = tptd.mesh(scan, 120.3, analysis=False, check=True)
    assert_same(py, cli)
    assert py.info["betti"] is None and report["betti"] is None
    assert_valid(py, report)


def test_a_closed_surface_and_a_curvilinear_grid_as_the_cli(tmp_path, scan):
    assert run_cli("scan.npy", "--alpha", 120.3, "-o", "ring.obj", cwd=tmp_path).returncode == 0
    cli, report = cli_mesh(tmp_path, "ring.obj", "--resolution", 24)
    with pytest.warns(tptd.MeshWarning, match="the triangles face inwards"):
        py = tptd.mesh_file(tmp_path / "ring.obj", resolution=24, check=True)
    assert_same(py, cli)
    assert_valid(py, report)
    # a quarter of a thick ring as Plot3D files (the README's duct, smaller)
    n = (9, 16, 6)
    r, t, z = np.meshgrid(10 + np.arange(n[0]) / 2, np.arange(n[1]) / 10, np.arange(n[2]) / 2,
                          indexing="ij")
    xyz = np.stack([r * np.cos(t), r * np.sin(t), z]).astype("<f4").transpose(0, 3, 2, 1)
    f = (np.sin(r / 2) * np.cos(3 * t) + z / 7).astype("<f4").T
    (tmp_path / "duct.xyz").write_bytes(np.array(n, "<i4").tobytes() + xyz.tobytes())
    (tmp_path / "duct.f").write_bytes(np.array(n + (1,), "<i4").tobytes() + f.tobytes())
    cli, report = cli_mesh(tmp_path, "duct.xyz", "--alpha", 0.3, "--beta", 0.7)
    py = tptd.mesh_file(tmp_path / "duct.xyz", 0.3, 0.7, check=True)
    assert_same(py, cli)
    assert_valid(py, report)
