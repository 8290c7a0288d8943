"""tptd: topology-correct tetrahedral meshes of interval volumes, numpy in, meshio out.

Volumes are 3-D numpy arrays indexed ``volume[i, j, k]`` = the grid point ``(x, y, z)``, as
``tptd-mesh`` reads a ``.npy`` file (so ``numpy.save`` then ``tptd-mesh`` gives the same mesh
as :func:`mesh`). The meshing, the checks and the messages are the Rust library's, the same as
``tptd-mesh``'s; options that would do nothing are refused with ``ValueError``.

Functions: :func:`mesh` (an array), :func:`mesh_file` (any input ``tptd-mesh`` reads),
:func:`read_volume` (a volume file as an array and its affine).
"""

from __future__ import annotations

import json
import os
import warnings
from typing import Callable, Optional, Sequence, Tuple

import numpy as np

from . import _tptd

__all__ = ["mesh", "mesh_file", "read_volume", "MeshWarning", "__version__"]
__version__ = _tptd.__version__

Progress = Callable[[str, float], object]


class MeshWarning(UserWarning):
    """A warning of a run (a bound equal to grid values, near a critical value, a quality
    target missed, ...): the same one line ``tptd-mesh`` prints."""


def _options(
    alpha, beta, levels, region_names, spacing, origin, affine, method, quality, min_angle,
    max_angle, quality_time, check, analysis, threads, field=None, function=None,
    resolution=None, voxel_size=None,
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
    check: bool = False,
    analysis: bool = True,
    threads: Optional[int] = None,
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
    ``[min_angle, max_angle]`` (``quality_time`` seconds at most); ``check=True`` runs the
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
    ``beta``, ``box``, ``domain``; or ``level1``, ... and the region names), so that
    ``meshio.write("x.msh", m)`` keeps them; ``m.info``: the run's report (the dict of
    ``tptd-mesh --report``: counts, volume, Betti numbers, angles, warnings, timings).
    Warnings are also issued as :class:`MeshWarning`.

    Raises ``ValueError`` for an argument that is invalid or would do nothing, and for an
    empty interval or a mesh failing ``check``, with ``tptd-mesh``'s one-line message
    (parameters named the Python way).
    """
    volume = np.asarray(volume)
    if not volume.dtype.isnative:  # big-endian data: the same values in native byte order
        volume = volume.astype(volume.dtype.newbyteorder("="))
    if volume.dtype == np.float16:  # read as float32, like the other narrow types
        volume = volume.astype(np.float32)
    if affine is not None and (
        tuple(origin) != (0.0, 0.0, 0.0) or tuple(spacing) != (1.0, 1.0, 1.0)
    ):
        raise ValueError("affine excludes spacing and origin: give the affine or those two")
    opts = _options(
        alpha, beta, levels, region_names,
        None if affine is not None else spacing, origin, affine, method, quality, min_angle,
        max_angle, quality_time, check, analysis, threads,
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
    check: bool = False,
    analysis: bool = True,
    threads: Optional[int] = None,
    field: Optional[str] = None,
    function=None,
    resolution: Optional[int] = None,
    voxel_size: Optional[float] = None,
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
        resolution, voxel_size,
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
