#!/usr/bin/env bash
# Epoch time per stage and peak memory at scale: generates Barabasi-Albert snapshots (m = 10) with
# 10^4, 10^5 and 10^6 particles (about 10^5, 10^6 and 10^7 links), then runs `r1 epoch` on each
# and prints the per-stage seconds from its manifest (total = the stages before writing) and the
# peak resident memory. With --no-field: the neural field's training is timed by itself
# (spec/neural.md R1-NRF-013).
# Usage: bench/epoch_scale.sh [R1_BINARY] [WORK_DIR] [SIZES...]   (sizes default: 10000 100000 1000000)
# EPOCH_FLAGS adds options to every `r1 epoch`, e.g. EPOCH_FLAGS=--parallel.
set -euo pipefail
r1=${1:-build/cli/r1}
work=${2:-$(mktemp -d)}
shift $(( $# > 2 ? 2 : $# ))
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(10000 100000 1000000)
mkdir -p "$work"
echo "r1 epoch scale: $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f GiB", $2/1048576}' /proc/meminfo), work dir $work"
printf '%-9s %-9s %7s %7s %8s %7s %7s %8s %9s %8s %8s\n' particles links read digest spectral focus frame encoding hierarchy total peak_MiB
for n in "${sizes[@]}"; do
  g="$work/ba-$n.graph"
  [ -f "$g" ] || "$r1" gen ba --n "$n" --m 10 -o "$g" >/dev/null
  /usr/bin/time -f '%M' -o "$work/rss-$n" "$r1" epoch "$g" -q --no-field ${EPOCH_FLAGS:-} -o "$work/ba-$n.epoch"
  python3 - "$work/ba-$n.epoch/manifest.json" "$(cat "$work/rss-$n")" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
t = m["timings_s"]
s = m["snapshot"]
cols = [t.get(k, 0.0) for k in ("read", "digest", "spectral", "focus", "frame", "encoding", "hierarchy")]
print("%-9d %-9d %7.2f %7.2f %8.2f %7.2f %7.2f %8.2f %9.2f %8.2f %8.0f" % (
    s["particles"], s["links"], *cols, sum(cols), int(sys.argv[2]) / 1024))
PY
done
