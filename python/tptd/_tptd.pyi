"""Type stubs of the native module tptd._tptd (use the functions of the package tptd)."""

from typing import Any, Callable, Optional, Tuple, Union

import numpy as np

__version__: str

def mesh_volume(
    volume: np.ndarray,
    options: dict[str, Any],
    progress: Optional[Callable[[str, float], object]] = None,
) -> dict[str, Any]: ...
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
