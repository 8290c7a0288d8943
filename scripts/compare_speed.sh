#!/usr/bin/env bash
# Meshing speed of two tptd-mesh builds, alternating runs in one session (timings on a shared
# machine drift; compare the ratio, not the seconds):
#
#   scripts/compare_speed.sh OLD_BIN NEW_BIN [REPS]      # default 5 repetitions
#
# ctd, -j 2, --no-analysis, binary .vtu, on benchmarks/data/noisy_256.npy (make it with
# `python3 benchmarks/make_data.py --sizes 256`) and the MNI152 T1 and white-matter templates
# of the nilearn package; then `--quality` on the demo and benchmarks/data/thin/smooth48.npy
# (`python3 benchmarks/thin_intervals.py`). Prints the median time of the mesh stage (of the
# quality pass for the `--quality` cases; from --report) and the wall time of each build, and
# their ratio.
set -euo pipefail
cd "$(dirname "$0")/.."
OLD=$(realpath "$1"); NEW=$(realpath "$2"); REPS=${3:-5}
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT
MNI=$(python3 -c "import nilearn, os; print(os.path.dirname(nilearn.__file__))")/datasets/data
CASES=(
  "benchmarks/data/noisy_256.npy --alpha -2 --beta 2"
  "benchmarks/data/noisy_256.npy --beta 0"
  "$MNI/mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz --alpha 151.0135 --beta 201.0135"
  "$MNI/mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz --alpha 127.0135"
  "--demo --quality"
  "benchmarks/data/thin/smooth48.npy --alpha -0.3 --beta 0.3 --quality"
)
for c in "${CASES[@]}"; do
  for rep in $(seq "$REPS"); do
    for which in old new; do
      bin=$OLD; [ "$which" = new ] && bin=$NEW
      s=$(date +%s.%N)
      # shellcheck disable=SC2086
      "$bin" $c -o "$TMP/out.vtu" --no-analysis -q -j 2 --report "$TMP/r.json"
      e=$(date +%s.%N)
      python3 -c "import json,sys; r=json.load(open('$TMP/r.json')); t=r['timings_seconds']; print('$which', sys.argv[1], r['tets'], t['quality'] if '--quality' in sys.argv[1] else t['mesh'], $e-$s)" "${c%% *}:${c#* }" >>"$TMP/runs.txt"
    done
  done
done
python3 - "$TMP/runs.txt" <<'PY'
import collections, statistics, sys
runs = collections.defaultdict(list)
for line in open(sys.argv[1]):
    which, rest = line.split(" ", 1)
    case, tets, mesh, wall = rest.rsplit(" ", 3)
    runs[(case, int(tets), which)].append((float(mesh), float(wall)))
for case, tets in sorted({(c, t) for c, t, _ in runs}):
    med = {w: [statistics.median(x[i] for x in runs[(case, tets, w)]) for i in (0, 1)] for w in ("old", "new")}
    stage = "quality" if "--quality" in case else "mesh"
    print(f"{case.split('/')[-1]}: {tets} tets; {stage} s old {med['old'][0]:.3f} new {med['new'][0]:.3f} "
          f"(ratio {med['new'][0] / med['old'][0]:.3f}); wall s old {med['old'][1]:.3f} "
          f"new {med['new'][1]:.3f} (ratio {med['new'][1] / med['old'][1]:.3f})")
PY
