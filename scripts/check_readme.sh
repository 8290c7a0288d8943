#!/usr/bin/env bash
# Runs the README's commands so that they cannot drift from the programs.
#
# Every ```sh block of README.md (or of the file given as $1) runs, in order, in one bash
# session (set -euo pipefail) that starts in the repository root, as a reader would type
# them: `cd` and `export` carry over from block to block. Each line `#> TEXT` of a block is
# an expected output: TEXT must appear in what that block printed (stdout and stderr). The
# block that is only `scripts/test.sh` is skipped: that is the test suite, which runs this
# script.
#
# Release builds stand in for debug ones, so that the check reuses the test suite's build:
# `cargo ... --release` runs as `cargo ... --profile test` and `target/release` reads
# `target/debug`. TMPDIR is a directory of this run, removed at the end, so the README's
# `mktemp -d` scratch directory goes too.
#
# Needs python3 with numpy and meshio (scripts/test.sh installs them).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
readme=$(realpath "${1:-README.md}")

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Split the sh blocks into files block-001.sh, block-002.sh, ... with their README lines.
awk -v dir="$work" '
  /^```sh[[:space:]]*$/ { n++; file = sprintf("%s/block-%03d.sh", dir, n); start = NR + 1; inblock = 1;
                          printf "" > file; print start > (file ".line"); next }
  inblock && /^```[[:space:]]*$/ { inblock = 0; close(file); next }
  inblock { print >> file }
  END { if (inblock) { print "unterminated sh block starting at line " start > "/dev/stderr"; exit 1 } }
' "$readme"

blocks=("$work"/block-*.sh)
if [ ! -e "${blocks[0]}" ]; then
  echo "check_readme: no sh blocks in $readme" >&2
  exit 1
fi

# One driver script: each block's output goes to its own file, and a marker file records the
# block that is running, so a failure can be named.
driver=$work/driver.sh
{
  echo 'set -euo pipefail'
  echo "export TMPDIR='$work/tmp'"
  echo "mkdir -p \"\$TMPDIR\""
  echo "cd '$root'"
  echo 'exec 3>&1 4>&2'
  echo 'cargo() {'
  echo '  local a=() x'
  echo '  for x in "$@"; do if [ "$x" = --release ]; then a+=(--profile test); else a+=("$x"); fi; done'
  echo '  command cargo "${a[@]}"'
  echo '}'
  for b in "${blocks[@]}"; do
    if [ "$(grep -v -e '^[[:space:]]*#' -e '^[[:space:]]*$' "$b")" = "scripts/test.sh" ]; then
      continue
    fi
    echo "echo '$b' > '$work/running'"
    echo "exec > '$b.out' 2>&1"
    sed -e 's#target/release#target/debug#g' "$b"
    echo 'exec 1>&3 2>&4'
  done
  echo "echo done > '$work/running'"
} > "$driver"

started=$SECONDS
status=0
bash "$driver" > "$work/driver.out" 2>&1 || status=$?
failed=0
running=$(cat "$work/running" 2>/dev/null || true)
if [ "$status" -ne 0 ] || [ "$running" != done ]; then
  line=$(cat "$running.line" 2>/dev/null || echo "?")
  echo "check_readme: FAILED: the sh block at $readme:$line exited with status $status; its output:" >&2
  sed 's/^/  | /' "$running.out" >&2 2>/dev/null || true
  sed 's/^/  | /' "$work/driver.out" >&2
  exit 1
fi

# Expected outputs.
checked=0
for b in "${blocks[@]}"; do
  [ -e "$b.out" ] || continue
  line=$(cat "$b.line")
  while IFS= read -r expect; do
    text=$(printf '%s' "$expect" | sed -e 's/^[[:space:]]*#>[[:space:]]*//')
    checked=$((checked + 1))
    if ! grep -qF -- "$text" "$b.out"; then
      echo "check_readme: FAILED: the sh block at $readme:$line did not print: $text" >&2
      sed 's/^/  | /' "$b.out" >&2
      failed=1
    fi
  done < <(grep -E '^[[:space:]]*#>' "$b" || true)
done
[ "$failed" -eq 0 ] || exit 1
echo "check_readme: ${#blocks[@]} sh blocks of $(basename "$readme") ran, $checked expected outputs found ($((SECONDS - started)) s)"
