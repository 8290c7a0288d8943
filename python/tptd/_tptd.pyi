"""Type stubs of the native module tptd._tptd (use the functions of the package tptd)."""

from typing import Any, Callable, Optional, Tuple

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
