#!/usr/bin/env bash
# The module layering (scripts/check_layers.py), the full test suite, the Python package's tests,
# then the README's commands.
# Installs what the tests need when it is missing: gmsh and CalculiX (Debian packages), numpy,
# meshio and VTK (PyPI), for the comparison with TetGen and fTetWild (tests/compare_peers.rs)
# tetgen, pytetwild, scikit-image, nilearn, nibabel and pyvista (PyPI), and for the Python
# package maturin and pytest (PyPI).
set -euo pipefail
cd "$(dirname "$0")/.."

missing=()
command -v gmsh >/dev/null 2>&1 || missing+=(gmsh)
command -v ccx >/dev/null 2>&1 || missing+=(calculix-ccx)
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing ${missing[*]} (apt)"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi
if ! python3 -c "import numpy, meshio, vtk" >/dev/null 2>&1; then
  echo "installing numpy meshio vtk (pip)"
  python3 -m pip install -q numpy meshio vtk
fi
if ! python3 -c "import scipy, tetgen, pytetwild, skimage, nilearn, nibabel, pyvista" >/dev/null 2>&1; then
  echo "installing scipy tetgen pytetwild scikit-image nilearn nibabel pyvista (pip)"
  python3 -m pip install -q scipy tetgen pytetwild scikit-image nilearn nibabel pyvista
fi

# No import circle between the top-level modules of src/, and the layer rules.
python3 scripts/check_layers.py

cargo test --all-targets "$@"

# The Python package (python/): built by maturin through pip, then its tests, which compare it
# with the tptd-mesh binary just built.
if ! python3 -c "import maturin, pytest" >/dev/null 2>&1; then
  echo "installing maturin pytest (pip)"
  python3 -m pip install -q maturin pytest
fi
python3 -m pip install -q --no-build-isolation ./python
python3 -m pytest -q python/tests

# Every command of the README, on small generated data (scripts/check_readme.sh).
scripts/check_readme.sh
