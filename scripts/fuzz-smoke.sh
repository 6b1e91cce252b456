#!/usr/bin/env bash
# Runs every libFuzzer executable in BUILD_DIR/fuzz for SECONDS each, starting from its committed
# corpus (read-only: new inputs go to a scratch directory). A crash fails the run.
set -euo pipefail
build=${1:-build-san}
secs=${2:-15}
root=$(cd "$(dirname "$0")/.." && pwd)
# The targets are the corpora's names (every target has one, R1-TEST-012): the build tree also
# holds test executables (r1_fuzz_replay) and CMake files under the same prefix.
targets=()
for dir in "$root"/fuzz/corpus/*/; do
  exe="$build/fuzz/r1_fuzz_$(basename "$dir")"
  if [ ! -x "$exe" ]; then echo "fuzz-smoke: $exe is not built (configure $build with -DR1_FUZZ=ON)" >&2; exit 1; fi
  targets+=("$exe")
done
if [ ${#targets[@]} -eq 0 ]; then echo "fuzz-smoke: no corpora under $root/fuzz/corpus" >&2; exit 1; fi
for exe in "${targets[@]}"; do
  name=$(basename "$exe"); name=${name#r1_fuzz_}
  scratch=$(mktemp -d)
  echo "fuzz-smoke: $name for ${secs}s" >&2
  "$exe" -max_total_time="$secs" -timeout=10 -rss_limit_mb=4096 -print_final_stats=0 \
         -artifact_prefix="$scratch/" "$scratch" "$root/fuzz/corpus/$name" >"$scratch/log" 2>&1 || {
    tail -40 "$scratch/log" >&2
    echo "fuzz-smoke: $name FAILED; reproducer in $scratch" >&2
    exit 1
  }
  rm -rf "$scratch"
done
echo "fuzz-smoke: ${#targets[@]} targets passed" >&2
