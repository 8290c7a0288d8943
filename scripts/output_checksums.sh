#!/usr/bin/env bash
# SHA-256 of every output tptd-mesh writes, for checking that a refactoring changes no byte.
#
#   scripts/output_checksums.sh [BIN] > sums.txt       # BIN default: target/release/tptd-mesh
#   diff sums-before.txt sums-after.txt
#
# Volumes: the demo, the MNI152 T1 and white-matter templates of the `nilearn` package and
# benchmarks/data/noisy_256.npy (make it with `python3 benchmarks/make_data.py --sizes 256`).
# Missing volumes are reported and skipped. Every method, every format (msh 4.1 and 2.2, inp,
# vtu). Then `--quality` on the demo and on two small volumes of benchmarks/data/thin/ (made by
# `python3 benchmarks/thin_intervals.py`), for every method, in msh 4.1 and vtu. Outputs go to a
# temporary folder and are deleted; only the sums are printed.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=$(realpath "${1:-target/release/tptd-mesh}")
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

NILEARN=$(python3 -c "import nilearn, os; print(os.path.dirname(nilearn.__file__))" 2>/dev/null || true)
MNI="$NILEARN/datasets/data"

# name | input ('demo' for the bundled one) | interval arguments
VOLUMES=(
  "demo|demo|"
  "mni_t1|$MNI/mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz|--alpha 151.0135 --beta 201.0135"
  "mni_wm|$MNI/mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz|--alpha 127.0135"
  "noisy_256|benchmarks/data/noisy_256.npy|--alpha -2 --beta 2"
)

# sums LABEL "EXTRA ARGS" "OUTPUTS" ENTRY...: the SHA-256 of each output of every method on each
# volume, one line each: `SUM  NAME METHOD [LABEL] OUTPUT`.
sums() {
  local label=$1 extra=$2 outs=$3 entry name input interval method out
  shift 3
  for entry in "$@"; do
    IFS='|' read -r name input interval <<<"$entry"
    local src=("$input")
    [ "$input" = demo ] && src=(--demo)
    if [ "$input" != demo ] && [ ! -f "$input" ]; then
      echo "missing  $name ($input)" >&2
      continue
    fi
    for method in ctd tptd std six five; do
      for out in $outs; do
        local args=()
        [ "$out" = v22.msh ] && args=(--msh-version 2.2)
        # shellcheck disable=SC2086
        "$BIN" "${src[@]}" $interval --method "$method" $extra -o "$TMP/out.${out##*.}" \
          --no-analysis -q "${args[@]}"
        echo "$(sha256sum <"$TMP/out.${out##*.}" | cut -c1-64)  $name $method ${label:+$label }$out"
        rm -f "$TMP/out.${out##*.}"
      done
    done
  done
}

sums "" "" "v41.msh v22.msh inp vtu" "${VOLUMES[@]}"

# name | input | interval arguments  (`--quality`: every method, msh 4.1 and vtu)
THIN=benchmarks/data/thin
QUALITY=(
  "demo|demo|"
  "t1_crop64|$THIN/t1_crop64.npy|--alpha 100.3 --beta 140.2"
  "smooth48|$THIN/smooth48.npy|--alpha -0.3 --beta 0.3"
)
sums quality --quality "msh vtu" "${QUALITY[@]}"
