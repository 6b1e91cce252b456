#!/usr/bin/env bash
# The viewer's browser tests (spec/viewer.md R1-VIEW-060..066): makes the crystal epoch and a second
# one, then drives `r1 view` with headless Chromium (viewer/tests/view_test.mjs).
#   viewer/tests/run-browser-tests.sh R1 WORK_DIR
# Without Node.js, Chromium or playwright-core (scripts/install-deps.sh installs them) it exits 77,
# which CTest reports as skipped, unless R1_REQUIRE_BROWSER=1 (make test sets it): then it fails.
set -euo pipefail
r1=$1
work=$2
here=$(cd "$(dirname "$0")" && pwd)
chromium=${R1_CHROMIUM:-/usr/bin/chromium}
missing=""
command -v node >/dev/null || missing="node"
[ -x "$chromium" ] || missing="$missing chromium ($chromium)"
[ -d "$here/node_modules/playwright-core" ] || missing="$missing playwright-core (npm ci --prefix viewer/tests)"
if [ -n "$missing" ]; then
  if [ "${R1_REQUIRE_BROWSER:-0}" = 1 ]; then
    echo "viewer browser tests: missing$missing, and R1_REQUIRE_BROWSER=1" >&2
    exit 1
  fi
  echo "viewer browser tests skipped: missing$missing (scripts/install-deps.sh installs them)"
  exit 77
fi
rm -rf "$work"
mkdir -p "$work"
"$r1" gen crystal -o "$work/crystal.graph" >/dev/null
"$r1" epoch "$work/crystal.graph" --overlay crystal-v5 --no-field -o "$work/crystal.epoch" >/dev/null
"$r1" gen sbm --n 240 --k 3 --p-in 0.12 --p-out 0.01 -o "$work/sbm.graph" >/dev/null
"$r1" epoch "$work/sbm.graph" --no-field -o "$work/sbm.epoch" >/dev/null
# T0 content (R1-VIEW-070..072) for three crystal particles, by id: an image (a 48x32 frame of the
# second epoch), a text, and a file that is not there; the epoch is made again with it.
mkdir -p "$work/content"
"$r1" render "$work/sbm.epoch" --size 48x32 --no-labels -q -o "$work/content/picture.png"
printf 'T0 <b>text</b> of a particle\nsecond line\n' > "$work/content/notes.txt"
"$r1" export "$work/crystal.epoch" --tsv - | awk -F'\t' '
  $2 == "Math entity 1" { print $1 "\tpicture.png" }
  $2 == "Math entity 2" { print $1 "\tnotes.txt" }
  $2 == "Math entity 3" { print $1 "\tgone.pdf" }' > "$work/content/side.tsv"
"$r1" epoch "$work/crystal.graph" --overlay crystal-v5 --content "$work/content/side.tsv" --no-field -o "$work/crystal.epoch" >/dev/null
exec node "$here/view_test.mjs" "$r1" "$work/crystal.epoch" "$work/sbm.epoch" "$work/out"
