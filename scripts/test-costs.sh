#!/usr/bin/env bash
# ctest runs the longest tests first when it knows their costs (BUILD/Testing/Temporary/
# CTestCostData.txt, which it writes after every run). A clean clone has none, so `make test`
# seeds each tree from a committed table (tests/costs/NAME.txt): on two cores the last long test
# then no longer starts when the others are done (R1-TEST-045). The table only orders the tests;
# a test missing from it runs after the listed ones, and ctest's own data replaces the seed after
# the first run.
#   scripts/test-costs.sh seed BUILD NAME   copy tests/costs/NAME.txt into BUILD unless it has data
#   scripts/test-costs.sh save BUILD NAME   write BUILD's tests of 1 s or more to tests/costs/NAME.txt
set -euo pipefail
mode=$1 build=$2 name=$3
root=$(cd "$(dirname "$0")/.." && pwd)
table="$root/tests/costs/$name.txt"
data="$build/Testing/Temporary/CTestCostData.txt"
case "$mode" in
  seed)
    if [ -s "$data" ] || [ ! -f "$table" ]; then exit 0; fi
    mkdir -p "$(dirname "$data")"
    { cat "$table"; echo "---"; } > "$data.tmp" && mv "$data.tmp" "$data"
    ;;
  save)
    if [ ! -s "$data" ]; then echo "test-costs: $data: no cost data (run ctest in $build first)" >&2; exit 2; fi
    mkdir -p "$(dirname "$table")"
    awk '/^---/ { exit } NF == 3 && $3 >= 1.0 { printf "%s 1 %.1f\n", $1, $3 }' "$data" | sort -k3,3 -g -r > "$table.tmp"
    mv "$table.tmp" "$table"
    echo "test-costs: $(wc -l < "$table") tests of 1 s or more in $table" >&2
    ;;
  *) echo "test-costs: unknown mode '$mode' (seed or save)" >&2; exit 2 ;;
esac
