#!/usr/bin/env bash
# Runs every libFuzzer executable in BUILD_DIR/fuzz for SECONDS each, starting from its committed
# corpus (read-only: new inputs go to a scratch directory), JOBS targets at a time (default: the
# cores; each libFuzzer process is single-threaded). A crash fails the run.
set -euo pipefail
build=${1:-build-san}
secs=${2:-12}
jobs=${3:-$(nproc)}
root=$(cd "$(dirname "$0")/.." && pwd)
# The targets are the corpora's names (every target has one, R1-TEST-012): the build tree also
# holds test executables (r1_fuzz_replay) and CMake files under the same prefix.
names=()
for dir in "$root"/fuzz/corpus/*/; do
  name=$(basename "$dir")
  if [ ! -x "$build/fuzz/r1_fuzz_$name" ]; then
    echo "fuzz-smoke: $build/fuzz/r1_fuzz_$name is not built (configure $build with -DR1_FUZZ=ON)" >&2; exit 1
  fi
  names+=("$name")
done
if [ ${#names[@]} -eq 0 ]; then echo "fuzz-smoke: no corpora under $root/fuzz/corpus" >&2; exit 1; fi

scratch_root=$(mktemp -d)
trap 'rm -rf "$scratch_root"' EXIT
# One target: its scratch directory keeps the log and any reproducer; exit status 0 or 1.
run_one() {
  local name=$1 scratch="$scratch_root/$1"
  mkdir -p "$scratch/new"
  echo "fuzz-smoke: $name for ${secs}s" >&2
  if "$build/fuzz/r1_fuzz_$name" -max_total_time="$secs" -timeout=10 -rss_limit_mb=4096 -print_final_stats=0 \
       -artifact_prefix="$scratch/" "$scratch/new" "$root/fuzz/corpus/$name" >"$scratch/log" 2>&1; then
    touch "$scratch/passed"
  fi
}

running=0
for name in "${names[@]}"; do
  run_one "$name" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then wait -n || true; running=$((running - 1)); fi
done
wait

failed=0
for name in "${names[@]}"; do
  [ -f "$scratch_root/$name/passed" ] && continue
  failed=1
  keep=$(mktemp -d)
  cp -r "$scratch_root/$name/." "$keep/"
  tail -40 "$keep/log" >&2
  echo "fuzz-smoke: $name FAILED; log and reproducer in $keep" >&2
done
[ "$failed" -eq 0 ] || exit 1
echo "fuzz-smoke: ${#names[@]} targets passed, $jobs at a time" >&2
