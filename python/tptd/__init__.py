"""tptd: topology-correct tetrahedral meshes of interval volumes, numpy in, meshio out.

Volumes are 3-D numpy arrays indexed ``volume[i, j, k]`` = the grid point ``(x, y, z)``, as
``tptd-mesh`` reads a ``.npy`` file (so ``numpy.save`` then ``tptd-mesh`` gives the same mesh
as :func:`mesh`). The meshing, the checks and the messages are the Rust library's, the same as
``tptd-mesh``'s; options that would do nothing are refused with ``ValueError``.

Functions: :func:`mesh` (an array), :func:`mesh_file` (any input ``tptd-mesh`` reads),
:func:`read_volume` (a volume file as an array and its affine), :func:`isosurface` (a level
set as triangles), :func:`critical_points` and :func:`critical_points_file` (``tptd-mesh
--critical``), :func:`inspect` (``tptd-mesh --inspect``), :func:`write` (a mesh through the
library's writers).
"""

from __future__ import annotations

import json
import os
import re
import warnings
from typing import Callable, Optional, Sequence, Tuple

import numpy as np

from . import _tptd

__all__ = [
    "mesh", "mesh_file", "read_volume", "isosurface", "critical_points", "critical_points_file",
    "inspect", "write", "MeshWarning", "__version__",
]
__version__ = _tptd.__version__

Progress = Callable[[str, float], object]


class MeshWarning(UserWarning):
    """A warning of a run (a bound equal to grid values, near a critical value, a quality
    target missed, ...): the same one line ``tptd-mesh`` prints."""


def _options(
    alpha, beta, levels, region_names, spacing, origin, affine, method, quality, min_angle,
    max_angle, quality_time, check, analysis, threads, field=None, function=None,
    resolution=None, voxel_size=None, memory_limit=None, max_edge=None, grading=1.5,
) -> dict:
    def floats(v, n=None):
        return None if v is None else [float(x) for x in v]

    return {
        "alpha": None if alpha is None else float(alpha),
        "beta": None if beta is None else float(beta),
        "levels": floats(levels),
        "region_names": None if region_names is None else [str(n) for n in region_names],
        "spacing": floats(spacing),
        "origin": floats(origin),
        "affine": None if affine is None else np.asarray(affine, dtype=float).tolist(),
        "method": str(method),
        "quality": bool(quality),
        "min_angle": float(min_angle),
        "max_angle": float(max_angle),
        "quality_time": None if quality_time is None else float(quality_time),
        "check": bool(check),
        "analysis": bool(analysis),
        "threads": None if threads is None else int(threads),
        "field": field,
        "function": None if function is None else os.fspath(function),
        "resolution": None if resolution is None else int(resolution),
        "voxel_size": None if voxel_size is None else float(voxel_size),
        "memory_limit": None if memory_limit is None else int(memory_limit),
        "max_edge": None if max_edge is None else float(max_edge),
        "grading": float(grading),
    }


def _to_meshio(d: dict, boundary: bool):
    import meshio

    for w in d["warnings"]:
        warnings.warn(w, MeshWarning, stacklevel=3)
    cells = [("tetra", d["tetra"])]
    cell_data = {
        "region": [d["tetra_region"]],
        "gmsh:physical": [d["tetra_tag"]],
        "gmsh:geometrical": [d["tetra_entity"]],
    }
    if boundary:
        cells.append(("triangle", d["triangle"]))
        cell_data["region"].append(d["triangle_region"])
        cell_data["gmsh:physical"].append(d["triangle_tag"])
        cell_data["gmsh:geometrical"].append(d["triangle_tag"])
    field_data = {name: np.array([tag, dim]) for name, tag, dim in d["names"]}
    m = meshio.Mesh(
        d["points"], cells, point_data={"f": d["f"]}, cell_data=cell_data,
        field_data=field_data,
    )
    m.info = json.loads(d["report"])
    return m


def _array(volume) -> np.ndarray:
    """``volume`` as an array the native module takes: native byte order, float16 as
    float32 (as the file readers read them)."""
    volume = np.asarray(volume)
    if not volume.dtype.isnative:  # big-endian data: the same values in native byte order
        volume = volume.astype(volume.dtype.newbyteorder("="))
    if volume.dtype == np.float16:  # read as float32, like the other narrow types
        volume = volume.astype(np.float32)
    return volume


def _placement(spacing, origin, affine):
    """The spacing to pass (``None`` with an affine), refusing an affine with either."""
    if affine is not None and (
        tuple(origin) != (0.0, 0.0, 0.0) or tuple(spacing) != (1.0, 1.0, 1.0)
    ):
        raise ValueError("affine excludes spacing and origin: give the affine or those two")
    return None if affine is not None else spacing


def mesh(
    volume,
    alpha: Optional[float] = None,
    beta: Optional[float] = None,
    *,
    levels: Optional[Sequence[float]] = None,
    region_names: Optional[Sequence[str]] = None,
    spacing: Sequence[float] = (1.0, 1.0, 1.0),
    origin: Sequence[float] = (0.0, 0.0, 0.0),
    affine=None,
    method: str = "ctd",
    quality: bool = False,
    min_angle: float = 15.0,
    max_angle: float = 155.0,
    quality_time: Optional[float] = None,
    max_edge: Optional[float] = None,
    grading: float = 1.5,
    check: bool = False,
    analysis: bool = True,
    threads: Optional[int] = None,
    memory_limit: Optional[int] = None,
    boundary: bool = True,
    progress: Optional[Progress] = None,
):
    """Mesh the interval volume ``{alpha <= f <= beta}`` of an array into tetrahedra.

    ``volume`` is a 3-D array indexed ``volume[i, j, k]`` = grid point ``(x, y, z)`` at
    ``origin + (i, j, k) * spacing`` (or ``affine @ (i, j, k, 1)`` when the 4x4 ``affine`` is
    given instead of ``spacing`` and ``origin``), as ``tptd-mesh`` reads a ``.npy`` file. Any
    integer or floating-point dtype. The library's grid holds the samples x fastest in their
    own type: a Fortran-ordered array (as ``tptd.read_volume``, nibabel's ``get_fdata()``
    and ``np.asarray(img.dataobj)`` give) of ``uint8``, ``int16``, ``uint16``, ``float32``
    or ``float64`` is used in place, without a copy; any other array is copied once (a
    transposing copy for a C-ordered one; ``int8`` is widened to ``int16``, 32- and 64-bit
    integers to ``float64``, ``float16`` to ``float32``, as the file readers do). The array
    must not be modified while the call runs (the GIL is released); it is not held after
    the call.

    ``alpha`` and/or ``beta`` bound one interval (a missing one is -inf / +inf); ``levels``
    (2 to 16 increasing values) mesh the regions between them in one conforming mesh instead,
    named by ``region_names``. ``method``: ``ctd`` (default), ``tptd``, ``std``, ``six``,
    ``five``. ``quality=True`` runs the quality pass towards dihedral angles in
    ``[min_angle, max_angle]`` (``quality_time`` seconds at most); ``max_edge`` grades the
    interior: cells deep inside one region are merged into cubes whose tets' mean edge length
    is ``max_edge`` (physical units) within a third (cubes of the power of two cells nearest
    it, at least ``(s - 1) / (grading - 1)`` cells from any cell a level passes through), as
    ``tptd-mesh --max-edge --grading``; ``check=True`` runs the
    library's checker and raises ``ValueError`` if the mesh fails it; ``analysis=False``
    skips the Betti numbers and angles of the report (faster). ``threads``: worker
    threads (default: all cores). ``progress(stage, fraction)`` is called at the start (0.0)
    and end (1.0) of each stage and as meshing goes; an exception it raises is raised when
    the run ends. The GIL is released while meshing.

    Returns a ``meshio.Mesh``: ``points`` (float64, n x 3), cell blocks ``tetra`` (int64,
    m x 4, positively oriented) and, with ``boundary=True``, ``triangle`` (the labelled
    boundary, outward, then the interfaces between regions); ``point_data["f"]`` (the field);
    ``cell_data["region"]`` (region of each tet from 0, as ``cell_data["region"]`` of the
    ``.vtu`` output; 0 for one interval), ``cell_data["gmsh:physical"]`` and
    ``"gmsh:geometrical"`` with ``field_data`` the ``.msh`` output's groups (``alpha``,
    ``beta``, ``box``, ``domain``; or ``level1``, ... and the region names: region ``k``'s
    tets have the physical tag ``k + 1``); ``m.info``: the run's report (the dict of
    ``tptd-mesh --report``: counts, volume, Betti numbers, angles, warnings, timings).
    Warnings are also issued as :class:`MeshWarning`.

    Files: ``meshio.write("x.vtu", m)`` keeps ``region`` and the tags as cell data. For Gmsh
    write with :func:`write` (``tptd.write(m, "x.msh")``, ``msh_version="2.2"``, ...): a
    volume group per region and a surface group per label, which ``meshio.read`` gives back
    as ``gmsh:physical`` and ``field_data``. meshio's own ``.msh`` writers (meshio 5.3) do
    not keep them: ``meshio.write("x.msh", m)`` writes ANSYS Fluent (meshio's first format
    for ``.msh``), ``file_format="gmsh"`` (4.1) refuses a mesh of two cell blocks without
    ``point_data["gmsh:dim_tags"]`` and keeps one tag per block, and ``"gmsh22"`` writes the
    groups but, with ``region`` or any other cell data beyond the tags, a file meshio cannot
    read back (its 2.2 reader splits cell data of several blocks wrongly).

    Before any work the run's memory is estimated (the grid, the mesh, the quality pass and
    the check) and compared with ``memory_limit`` (bytes; default: the memory available):
    a run that would not fit raises ``MemoryError``.

    Raises ``ValueError`` for an argument that is invalid or would do nothing, and for an
    empty interval or a mesh failing ``check``, with ``tptd-mesh``'s one-line message
    (parameters named the Python way).
    """
    volume = _array(volume)
    opts = _options(
        alpha, beta, levels, region_names, _placement(spacing, origin, affine), origin,
        affine, method, quality, min_angle, max_angle, quality_time, check, analysis, threads,
        memory_limit=memory_limit, max_edge=max_edge, grading=grading,
    )
    return _to_meshio(_tptd.mesh_volume(volume, opts, progress), boundary)


def mesh_file(
    path,
    alpha: Optional[float] = None,
    beta: Optional[float] = None,
    *,
    levels: Optional[Sequence[float]] = None,
    region_names: Optional[Sequence[str]] = None,
    spacing: Optional[Sequence[float]] = None,
    method: str = "ctd",
    quality: bool = False,
    min_angle: float = 15.0,
    max_angle: float = 155.0,
    quality_time: Optional[float] = None,
    max_edge: Optional[float] = None,
    grading: float = 1.5,
    check: bool = False,
    analysis: bool = True,
    threads: Optional[int] = None,
    field: Optional[str] = None,
    function=None,
    resolution: Optional[int] = None,
    voxel_size: Optional[float] = None,
    memory_limit: Optional[int] = None,
    boundary: bool = True,
    progress: Optional[Progress] = None,
):
    """Mesh a file ``tptd-mesh`` reads, in its physical coordinates, as :func:`mesh` does.

    ``path``: a volume (``.npy``, NRRD, NIfTI, MetaImage), a curvilinear grid (``.vts`` with
    ``field``; Plot3D ``.xyz`` with its ``function`` file) or a closed surface (``.obj``,
    ``.stl``, ``.ply``, meshed as the solid it bounds on a grid of ``resolution`` voxels or
    of ``voxel_size``). ``spacing`` replaces the file's. Same result and errors as
    :func:`mesh`, and ``OSError`` when the file cannot be read.
    """
    opts = _options(
        alpha, beta, levels, region_names, spacing, (0.0, 0.0, 0.0), None, method, quality,
        min_angle, max_angle, quality_time, check, analysis, threads, field, function,
        resolution, voxel_size, memory_limit, max_edge, grading,
    )
    return _to_meshio(_tptd.mesh_path(os.fspath(path), opts, progress), boundary)


def read_volume(path) -> Tuple[np.ndarray, np.ndarray]:
    """Read a volume file as ``tptd-mesh`` does: ``(array, affine)``.

    ``array`` is indexed ``[i, j, k]`` = grid point ``(x, y, z)``, in the type the file's
    samples are held in (Fortran order, no copy); ``affine`` is the 4x4 float64 matrix from
    index ``(i, j, k, 1)`` to physical coordinates. ``mesh(array, ..., affine=affine)`` gives
    the mesh of ``mesh_file(path, ...)``. Raises ``OSError`` when the file cannot be read and
    ``ValueError`` when it is malformed.
    """
    array, affine = _tptd.read_volume(os.fspath(path))
    return array, affine


def isosurface(
    volume,
    level: float,
    *,
    spacing: Sequence[float] = (1.0, 1.0, 1.0),
    origin: Sequence[float] = (0.0, 0.0, 0.0),
    affine=None,
    method: str = "ctd",
    caps: bool = False,
    threads: Optional[int] = None,
):
    """The level set ``{f = level}`` of an array as triangles: the surface ``tptd-mesh`` writes
    for ``VOLUME --alpha LEVEL -o OUT.obj`` (``.ply``, ``.stl``), i.e. the ``alpha`` boundary
    of the mesh of ``{level <= f}``, with the topology of the trilinear interpolant (``method``
    as in :func:`mesh`), normals towards increasing f. ``caps=True`` adds the triangles on
    the grid box that close it (``--caps``). ``volume``, ``spacing``, ``origin``, ``affine``
    and ``threads`` as in :func:`mesh`; the GIL is released while it works.

    Returns a ``meshio.Mesh``: ``points`` (float64, n x 3, numbered by first use), one cell
    block ``triangle`` (int64) and ``point_data["f"]``. Warnings (a level equal to grid values
    or near a critical value) are issued as :class:`MeshWarning`. Raises ``ValueError`` as
    :func:`mesh` does (e.g. a level above the data: the interval contains no part of the
    volume).
    """
    import meshio

    volume = _array(volume)
    opts = _options(
        level, None, None, None, _placement(spacing, origin, affine), origin, affine, method,
        False, 15.0, 155.0, None, False, False, threads,
    )
    d = _tptd.isosurface_volume(volume, opts, bool(caps))
    for w in d["warnings"]:
        warnings.warn(w, MeshWarning, stacklevel=2)
    return meshio.Mesh(d["points"], [("triangle", d["triangle"])], point_data={"f": d["f"]})


def _critical_options(
    spacing, origin, affine, *, min_value: Optional[float] = None,
    max_value: Optional[float] = None, kind=None, persistence: bool = False,
    min_persistence: Optional[float] = None, threads: Optional[int] = None,
) -> dict:
    """The options of a run of the critical points: the placement, and the filters and
    threads of :func:`critical_points` (the one list of them, which both functions take as
    keywords)."""
    if kind is not None and not isinstance(kind, str):
        kind = ",".join(str(k) for k in kind)
    return {
        "spacing": None if spacing is None else [float(x) for x in spacing],
        "origin": [float(x) for x in origin],
        "affine": None if affine is None else np.asarray(affine, dtype=float).tolist(),
        "min_value": None if min_value is None else float(min_value),
        "max_value": None if max_value is None else float(max_value),
        "kind": kind,
        "persistence": bool(persistence),
        "min_persistence": None if min_persistence is None else float(min_persistence),
        "threads": None if threads is None else int(threads),
    }


def critical_points(
    volume,
    *,
    spacing: Optional[Sequence[float]] = None,
    origin: Sequence[float] = (0.0, 0.0, 0.0),
    affine=None,
    **filters,
) -> list:
    """The critical points and regions of the trilinear field of an array (where the topology
    of ``{f >= w}`` or ``{f <= w}`` changes): the records ``tptd-mesh VOLUME --critical
    --json`` writes, one dict per point (``value``, ``kind``, ``position`` in physical
    coordinates, ``persistence``, ``superlevel``, ``sublevel``, ``region``, ...).

    ``volume``, ``origin`` and ``affine`` as in :func:`mesh` (``spacing`` defaults to 1).
    Keywords (``filters``), as the command line's: ``min_value`` / ``max_value`` (floats)
    hide points below / above; ``kind`` keeps only these kinds (a list or a comma-separated
    string of ``minimum``, ``maximum``, ``saddle``, ``face_saddle``, ``body_saddle``,
    ``region_minimum``, ``region_maximum``, ``region_saddle``); ``persistence=True``
    computes each point's persistence; ``min_persistence`` hides points below it (and
    implies ``persistence``); ``threads`` as in :func:`mesh`. An unknown keyword raises
    ``TypeError``; otherwise raises ``ValueError`` with ``tptd-mesh``'s one-line message.
    """
    volume = _array(volume)
    if affine is not None and (spacing is not None or tuple(origin) != (0.0, 0.0, 0.0)):
        raise ValueError("affine excludes spacing and origin: give the affine or those two")
    opts = _critical_options(spacing, origin, affine, **filters)
    return json.loads(_tptd.critical_volume(volume, opts))


def critical_points_file(path, *, spacing: Optional[Sequence[float]] = None, **filters) -> list:
    """:func:`critical_points` of a volume file ``tptd-mesh`` reads (``spacing`` replaces the
    file's; the same keywords ``filters``): the records of ``tptd-mesh PATH --critical
    --json``. Raises ``OSError`` when the file cannot be read, ``ValueError`` otherwise."""
    opts = _critical_options(spacing, (0.0, 0.0, 0.0), None, **filters)
    return json.loads(_tptd.critical_path(os.fspath(path), opts))


def _blocks(m, kind: str, width: int, key: Optional[str] = None):
    """The cells of type ``kind`` of every block, and their ``cell_data[key]`` (``None`` when
    a block has none)."""
    idx = [i for i, c in enumerate(m.cells) if c.type == kind]
    cells = [np.asarray(m.cells[i].data, dtype=np.int64).reshape(-1, width) for i in idx]
    cells = np.concatenate(cells) if cells else np.zeros((0, width), dtype=np.int64)
    data = m.cell_data.get(key) if key else None
    if data is None or not idx:
        return cells, None
    return cells, np.concatenate([np.ravel(np.asarray(data[i], dtype=np.int64)) for i in idx])


def _mesh_arrays(m, labels, levels=0, region_names=()) -> dict:
    """The arrays of a ``meshio.Mesh`` the native module takes: points, ``point_data["f"]``
    (if any), the ``tetra`` cells with their ``region``, the ``triangle`` cells with their
    label codes ``labels(tags)`` (from ``gmsh:physical``; -1: not labelled)."""
    if not any(c.type == "tetra" for c in m.cells):
        raise ValueError("mesh: no tetra cells")
    tetra, tetra_region = _blocks(m, "tetra", 4, "region")
    triangle, tags = _blocks(m, "triangle", 3, "gmsh:physical")
    _, triangle_region = _blocks(m, "triangle", 3, "region")
    f = m.point_data.get("f")
    return {
        "points": np.ascontiguousarray(m.points, dtype=np.float64),
        "f": None if f is None else np.ascontiguousarray(np.ravel(f), dtype=np.float64),
        "tetra": tetra,
        "tetra_region": tetra_region,
        "triangle": triangle,
        "triangle_label": labels(tags, len(triangle)),
        "triangle_region": triangle_region,
        "levels": int(levels),
        "region_names": [str(n) for n in region_names],
    }


def _groups(m, dim: int) -> dict:
    """The names of ``m.field_data``'s groups of dimension ``dim``, by tag."""
    out = {}
    for name, v in m.field_data.items():
        v = np.ravel(v)
        if len(v) >= 2 and int(v[1]) == dim:
            out[int(v[0])] = name
    return out


def _levels(m, tetra_region) -> Tuple[int, list]:
    """The levels of the run a mesh of :func:`mesh` comes from (0 for one interval) and its
    regions' names: from ``m.info`` (the report), else from the group names."""
    info = getattr(m, "info", None)
    if isinstance(info, dict) and info.get("levels"):
        return len(info["levels"]), [r["name"] for r in info.get("regions", [])]
    surfaces = _groups(m, 2)
    level_tags = [t for t, n in surfaces.items() if re.fullmatch(r"level[0-9]+", n)]
    several = tetra_region is not None and len(tetra_region) and tetra_region.max() > 0
    if not level_tags and not several:
        return 0, []
    box = [t - 1 for t, n in surfaces.items() if n == "box"]
    regions = [] if tetra_region is None or not len(tetra_region) else [tetra_region.max() + 2]
    count = max(level_tags + box + regions)
    volumes = _groups(m, 3)
    return count, [volumes.get(k + 1, f"region{k + 1}") for k in range(count - 1)]


def write(
    mesh,
    path,
    *,
    msh_version: Optional[str] = None,
    vtu_encoding: Optional[str] = None,
    ascii: bool = False,
) -> None:
    """Write a mesh of :func:`mesh` with the library's writers, as ``tptd-mesh`` writes its
    output: the format by the extension of ``path``, ``.msh`` (``msh_version``: ``4.1``,
    the default, ``2.2`` or ``4.1-binary``), ``.inp``, ``.vtu`` (``vtu_encoding``:
    ``base64``, the default, ``zlib`` or ``raw``), or the level sets as ``.obj``, ``.ply``,
    ``.stl`` (``ascii=True``: text ``.ply`` / ``.stl``). The same mesh gives the same bytes
    as ``tptd-mesh ... -o path``. The file is written under a temporary name in the same
    folder and renamed when complete: a failure leaves no file (and an existing one as it
    was). The GIL is released while writing.

    ``mesh``: a ``meshio.Mesh`` with a ``tetra`` block and ``points``; its ``triangle`` block
    with ``cell_data["gmsh:physical"]`` (the labelled boundary, then the interfaces),
    ``cell_data["region"]``, ``point_data["f"]`` (zeros if absent) and ``field_data`` as
    :func:`mesh` gives them; the levels of a mesh of several regions are read from
    ``mesh.info`` (else from the group names). Raises ``ValueError`` for an unknown
    extension, an option of another format or an inconsistent mesh, ``OSError`` when the
    file cannot be written, each with ``tptd-mesh``'s one-line message.
    """
    tetra_region = _blocks(mesh, "tetra", 4, "region")[1]
    levels, names = _levels(mesh, tetra_region)
    count = max(levels, 2)

    def codes(tags, n):
        if tags is None:
            return np.full(n, -1, dtype=np.int64)
        return np.where((tags >= 1) & (tags <= count + 1), tags - 1, -1).astype(np.int64)

    arrays = _mesh_arrays(mesh, codes, levels, names)
    options = {"msh_version": msh_version, "vtu_encoding": vtu_encoding, "ascii": bool(ascii)}
    _tptd.write_mesh(os.fspath(path), arrays, options)


def _is_path(x) -> bool:
    return isinstance(x, (str, bytes, os.PathLike))


def inspect(
    mesh,
    volume=None,
    *,
    alpha: Optional[float] = None,
    beta: Optional[float] = None,
    spacing: Optional[Sequence[float]] = None,
    origin: Sequence[float] = (0.0, 0.0, 0.0),
    affine=None,
    threads: Optional[int] = None,
) -> dict:
    """Inspect a tetrahedral mesh as ``tptd-mesh --inspect MESH [--volume VOLUME --alpha A
    --beta B] --json`` does: counts, volume, dihedral angles and their percentiles, quality,
    the library checker's verdict (``valid``, ``problems``: conformity, orientation, closed
    manifold boundary, embedding), Betti numbers; with the volume it models and the interval
    ``[alpha, beta]``, the trilinear interval's Betti numbers and volume and the boundary's
    distance to the level sets. Returns the command line's JSON object of the mesh as a dict.

    ``mesh``: a file the command line reads (``.msh``, ``.inp``, ``.vtu``, ``.vtk``, Medit
    ``.mesh``, TetGen ``.node``/``.ele``) or a ``meshio.Mesh`` (its ``tetra`` cells and
    points; ``point_data["f"]``; its triangles in groups named ``alpha``, ``beta``, ``box``
    by ``field_data`` and ``cell_data["gmsh:physical"]`` are its labelled boundary, as a
    ``.msh`` file's groups), named ``mesh`` in the result. ``volume``: a volume file (whose
    spacing ``spacing`` replaces) or an array (placed by ``spacing``, ``origin`` or
    ``affine`` as in :func:`mesh`). Raises ``ValueError`` for arguments the command line
    refuses (e.g. an interval without a volume) or malformed files, ``OSError`` for a file
    that cannot be read.
    """
    if _is_path(mesh):
        m = os.fspath(mesh)
    else:
        surfaces = _groups(mesh, 2)
        by_tag = {t: ["alpha", "beta", "box"].index(n.lower())
                  for t, n in surfaces.items() if n.lower() in ("alpha", "beta", "box")}

        def codes(tags, n):
            if tags is None:
                return np.full(n, -1, dtype=np.int64)
            return np.array([by_tag.get(int(t), -1) for t in tags], dtype=np.int64)

        m = _mesh_arrays(mesh, codes)
    if volume is not None and _is_path(volume):
        if affine is not None or tuple(origin) != (0.0, 0.0, 0.0):
            raise ValueError("origin and affine apply only to an array volume")
        volume = os.fspath(volume)
    elif volume is not None:
        volume = _array(volume)
        if affine is not None and (spacing is not None or tuple(origin) != (0.0, 0.0, 0.0)):
            raise ValueError("affine excludes spacing and origin: give the affine or those two")
    options = {
        "alpha": None if alpha is None else float(alpha),
        "beta": None if beta is None else float(beta),
        "spacing": None if spacing is None else [float(x) for x in spacing],
        "origin": [float(x) for x in origin],
        "affine": None if affine is None else np.asarray(affine, dtype=float).tolist(),
        "threads": None if threads is None else int(threads),
    }
    return json.loads(_tptd.inspect_mesh(m, volume, options))
