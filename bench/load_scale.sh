#!/usr/bin/env bash
# Load time and memory at scale: generates Barabasi-Albert snapshots with 10^6 and 10^7 links
# (m = 10) as .graph and .tsv, then runs `r1 info --timings` on each (read, layout graph, digest,
# peak resident memory). Usage: bench/load_scale.sh [R1_BINARY] [WORK_DIR]
set -euo pipefail
r1=${1:-build/cli/r1}
work=${2:-$(mktemp -d)}
mkdir -p "$work"
echo "r1 load scale: $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f GiB", $2/1048576}' /proc/meminfo), work dir $work"
printf '%-10s %-6s %10s %9s %9s %9s %10s\n' links format size load_s graph_s digest_s peak_MiB
for n in 100000 1000000; do
  for ext in graph tsv; do
    f="$work/ba-$n.$ext"
    [ -f "$f" ] || "$r1" gen ba --n "$n" --m 10 -o "$f" >/dev/null
    line=$("$r1" info "$f" --timings --json | python3 -c '
import json, sys
j = json.load(sys.stdin); t = j["timing"]
print(j["links"], t["load_s"], t["graph_s"], t["digest_s"], t["peak_rss_mib"])')
    read -r links load graph digest rss <<<"$line"
    printf '%-10s %-6s %10s %9.2f %9.2f %9.2f %10.0f\n' "$links" "$ext" "$(du -h "$f" | cut -f1)" "$load" "$graph" "$digest" "$rss"
  done
done
