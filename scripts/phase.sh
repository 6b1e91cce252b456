#!/usr/bin/env bash
# Runs one phase of `make test` (or any make target) and prints its wall time, so CI growth shows
# phase by phase (spec/testing.md R1-TEST-045). Usage: scripts/phase.sh NAME COMMAND [ARGS...]
# The time is also appended to $R1_PHASE_LOG (default build/phases.log) as "NAME SECONDS".
set -uo pipefail
name=$1; shift
log=${R1_PHASE_LOG:-build/phases.log}
start=$(date +%s)
echo "== phase $name" >&2
"$@"
rc=$?
secs=$(( $(date +%s) - start ))
mkdir -p "$(dirname "$log")"
echo "$name $secs" >>"$log"
if [ $rc -ne 0 ]; then
  echo "== phase $name FAILED after ${secs} s (exit $rc)" >&2
  exit $rc
fi
echo "== phase $name: ${secs} s" >&2
