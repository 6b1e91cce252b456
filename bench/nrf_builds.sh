#!/usr/bin/env bash
# The neural field across two builds of r1 (spec/neural.md R1-NRF-012): each build trains the field
# of the same epoch; the script says whether the two files are the same bytes, then draws three
# far views (`--orbit 3`, 480x270) with each field through the first build and prints the
# CIEDE2000 between the two frames of each view (covered mean and largest pixel). Build the second
# tree with other flags or another compiler, for example
#   cmake -S . -B build-native -G Ninja -DR1_BUILD_TESTS=OFF -DR1_BUILD_BENCH=OFF -DCMAKE_CXX_FLAGS=-march=native
#   CC=clang CXX=clang++ cmake -S . -B build-clang -G Ninja -DR1_BUILD_TESTS=OFF -DR1_BUILD_BENCH=OFF
# and build its cli/r1.
# Usage: bench/nrf_builds.sh R1_A R1_B EPOCH_DIR DISTANCE [WORK_DIR]
set -euo pipefail
if [ $# -lt 4 ]; then
  echo "usage: bench/nrf_builds.sh R1_A R1_B EPOCH_DIR DISTANCE [WORK_DIR]" >&2
  exit 2
fi
a=$1 b=$2 epoch=$3 distance=$4
work=${5:-$(mktemp -d)}
mkdir -p "$work"
for r1 in "$a" "$b"; do
  [ -x "$r1" ] || { echo "nrf_builds: $r1 is not an executable" >&2; exit 2; }
done
echo "nrf_builds: training with $a" >&2
"$a" train-field "$epoch" -o "$work/a.nrf" -q
echo "nrf_builds: training with $b" >&2
"$b" train-field "$epoch" -o "$work/b.nrf" -q
if cmp -s "$work/a.nrf" "$work/b.nrf"; then echo "field bytes: the same"; else echo "field bytes: differ"; fi
for f in a b; do
  "$a" render "$epoch" --distance "$distance" --orbit 3 --size 480x270 --field neural --field-file "$work/$f.nrf" -q \
    -o "$work/$f.png" > /dev/null
done
printf 'view\tcovered_mean_dE00\tmax_dE00\n'
for k in 000 001 002; do
  "$a" diff "$work/a-$k.png" "$work/b-$k.png" --json | python3 -c '
import json, sys
d = json.load(sys.stdin)
print("%s\t%.4f\t%.3f" % (sys.argv[1], d["covered_mean_2000"], d["max_2000"]))' "$k"
done
