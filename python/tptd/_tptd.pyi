"""Type stubs of the native module tptd._tptd (use the functions of the package tptd)."""

from typing import Any, Callable, Optional, Tuple, Union

import numpy as np

__version__: str

def mesh_volume(
    volume: np.ndarray,
    options: dict[str, Any],
    progress: Optional[Callable[[str, float], object]] = None,
) -> dict[str, Any]:
    """The mesh as numpy arrays: ``points`` (float64, n x 3), ``f``, ``tetra`` (int64,
    m x 4), ``tetra_region`` (int32, region of each tet from 0: ``cell_data["region"]``),
    ``tetra_tag`` and ``tetra_entity`` (int32, the ``.msh`` output's physical and elementary
    tags: region + 1, or the ``domain`` tag), ``triangle``, ``triangle_region``,
    ``triangle_tag``, ``names`` (``(name, tag, dimension)`` of each group), ``report`` (JSON
    text) and ``warnings``; ``tptd.mesh`` makes the ``meshio.Mesh`` of them."""
    ...

def mesh_path(
    path: str,
    options: dict[str, Any],
    progress: Optional[Callable[[str, float], object]] = None,
) -> dict[str, Any]: ...
def read_volume(path: str) -> Tuple[np.ndarray, np.ndarray]: ...
def isosurface_volume(
    volume: np.ndarray, options: dict[str, Any], caps: bool = False
) -> dict[str, Any]: ...
def critical_volume(volume: np.ndarray, options: dict[str, Any]) -> str: ...
def critical_path(path: str, options: dict[str, Any]) -> str: ...
def inspect_mesh(
    mesh: Union[str, dict[str, Any]],
    volume: Union[str, np.ndarray, None],
    options: dict[str, Any],
) -> str: ...
def write_mesh(path: str, mesh: dict[str, Any], options: dict[str, Any]) -> None: ...
