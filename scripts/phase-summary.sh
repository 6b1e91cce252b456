#!/usr/bin/env bash
# Prints the phase times scripts/phase.sh logged and their total (R1-TEST-045), then clears the log.
set -euo pipefail
log=${R1_PHASE_LOG:-build/phases.log}
[ -f "$log" ] || exit 0
awk '{ printf "  %-14s %5d s\n", $1, $2; t += $2 } END { printf "  %-14s %5d s (%d min %d s)\n", "total", t, t / 60, t % 60 }' "$log" >&2
rm -f "$log"
