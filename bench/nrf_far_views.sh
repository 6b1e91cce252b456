#!/usr/bin/env bash
# The neural field's far views against the analytic field's (spec/neural.md R1-NRF-040): for every
# graph of a suite (its `gen` lines) and every epoch named after it, make the epoch with its field
# (`r1 epoch`, the default training), draw three orbit views at each DISTANCE:SIZE with the
# analytic field (the oracle) and with the neural one, and print the covered mean CIEDE2000 of
# each view (R-1.0 7.4's bar: at most 2) and which field drew the neural frame (it draws only
# pure T-infinity views; `r1 render` says why where the analytic field drew it instead).
# Usage: bench/nrf_far_views.sh R1 [SUITE_TOML] [EPOCH_DIR...]
#   R1_VIEWS="400000:480x270 400000:128x72 2000000:480x270" (the default) sets the views;
#   WORK (default: a temporary directory) keeps the epochs and frames.
set -euo pipefail
if [ $# -lt 1 ]; then
  echo "usage: bench/nrf_far_views.sh R1 [SUITE_TOML] [EPOCH_DIR...]" >&2
  exit 2
fi
r1=$1
suite=${2:-spec/suites/small.toml}
shift $(($# < 2 ? $# : 2))
[ -x "$r1" ] || { echo "nrf_far_views: $r1 is not an executable" >&2; exit 2; }
[ -f "$suite" ] || { echo "nrf_far_views: $suite: no such suite" >&2; exit 2; }
views=${R1_VIEWS:-"400000:480x270 400000:128x72 2000000:480x270"}
work=${WORK:-$(mktemp -d)}
mkdir -p "$work"
epochs=()
# The suite's generated graphs: one epoch each, named as the suite names the graph.
while IFS=$'\t' read -r name gen; do
  echo "nrf_far_views: epoch of $name ($gen)" >&2
  # shellcheck disable=SC2086  # gen is the generator's words
  "$r1" gen $gen -o "$work/$name.graph" > /dev/null
  rm -rf "$work/$name.epoch"
  "$r1" epoch "$work/$name.graph" -o "$work/$name.epoch" > /dev/null
  epochs+=("$work/$name.epoch")
done < <(python3 -c '
import sys, tomllib
with open(sys.argv[1], "rb") as f:
    suite = tomllib.load(f)
for g in suite.get("graph", []):
    if "gen" in g:
        print(g["name"] + "\t" + g["gen"])' "$suite")
for e in "$@"; do
  [ -f "$e/field.nrf" ] || { echo "nrf_far_views: $e has no field.nrf (r1 train-field $e)" >&2; exit 2; }
  epochs+=("$e")
done
printf 'epoch\tdistance\tsize\tview\tfield\tcovered_mean_dE00\n'
for e in "${epochs[@]}"; do
  base=$(basename "$e")
  for v in $views; do
    d=${v%%:*} size=${v#*:}
    out="$work/$base-$d-$size"
    "$r1" render "$e" --distance "$d" --orbit 3 --size "$size" --field analytic -q -o "$out-a.png" > /dev/null
    # `r1 render` says per view which field drew it, in view order.
    mapfile -t drew < <("$r1" render "$e" --distance "$d" --orbit 3 --size "$size" --field neural -o "$out-n.png" 2>&1 |
      sed -n 's/^ *field: //p')
    i=0
    for k in 000 001 002; do
      # r1 diff exits 1 where some pixel is over its threshold: the JSON is the answer here.
      dE=$({ "$r1" diff "$out-a-$k.png" "$out-n-$k.png" --json || true; } |
        python3 -c 'import json, sys; print("%.3f" % json.load(sys.stdin)["covered_mean_2000"])')
      field=${drew[$i]:-?}
      printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$base" "$d" "$size" "$k" "$field" "$dE"
      i=$((i + 1))
    done
  done
done
