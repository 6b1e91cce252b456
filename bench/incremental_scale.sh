#!/usr/bin/env bash
# Incremental epoch against the full epoch at scale (spec/incremental.md): for Barabasi-Albert
# snapshots (m = 10) of each size, the full epoch (PREV), a batch of 10 links added between
# particles drawn with a fixed seed outside the anchor set, and `r1 epoch NEXT --from PREV` with the
# given update options; prints |N_h|/|N_(h+1)| (region), the stages of both epochs (seconds, from their manifests; `cert` is
# the incremental epoch's carried sums and rows of N_(h+1) after the update, `spectral` its local
# work, `carry` the O(|P|) gathering of PREV's vectors and image by particle),
# the sum of the stages, the wall time of the whole command (reading and writing included) and the
# ratio of the two. Every epoch with --no-field: the neural field's training and local update are
# timed by themselves (spec/neural.md). Existing snapshots and PREV epochs in WORK_DIR are reused, with the wall time
# of the run that made them (a full epoch of 10^6 particles takes about half an hour on two cores).
# Usage: bench/incremental_scale.sh [R1_BINARY] [WORK_DIR] [SIZES...]   (sizes default: 10000 100000)
# UPDATE_FLAGS: the update options (default: --hops 1 --keep-local --full-norm 1000, which time the
# local path on graphs where no certificate holds); BACKEND: the backend (default cpu); KIND: ba
# (default) or rgg (3D geometric graphs of mean degree about 20 at every size: bounded degree).
# LINKS=2: a second link of the chain as well (ten more added links, seed 8, from the first
# incremental epoch), printed as `inc2` with the update stages in milliseconds.
set -euo pipefail
r1=${1:-build/cli/r1}
work=${2:-$(mktemp -d)}
shift $(( $# > 2 ? 2 : $# ))
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(10000 100000)
flags=${UPDATE_FLAGS:---hops 1 --keep-local --full-norm 1000}
backend=${BACKEND:-cpu}
kind=${KIND:-ba}
mkdir -p "$work"
echo "r1 incremental scale: $(nproc) cores, $kind graphs, backend $backend, update flags: $flags, work dir $work"
printf '%-9s %-7s %15s %7s %7s %6s %6s %6s %8s %6s %6s %8s %9s %8s %8s %6s\n' particles path region read digest prev batch \
  carry spectral cert focus encoding hierarchy stages wall ratio
for n in "${sizes[@]}"; do
  g="$work/$kind-$n.graph"
  if [ ! -f "$g" ]; then
    case $kind in
      ba) "$r1" gen ba --n "$n" --m 10 -o "$g" >/dev/null ;;
      # Mean degree about 20 at every size: n (4/3) pi r^3 = 20 (a little less near the cube's faces).
      rgg) "$r1" gen rgg --n "$n" --radius "$(python3 -c "import math; print((15 / (math.pi * $n)) ** (1 / 3))")" -o "$g" >/dev/null ;;
      *) echo "incremental_scale: KIND is ba or rgg, not $kind" >&2; exit 2 ;;
    esac
  fi
  [ -f "$work/$kind-$n.epoch/manifest.json" ] ||
    /usr/bin/time -f '%e' -o "$work/wall-$kind-$n" "$r1" epoch "$g" -q --no-field --backend "$backend" -o "$work/$kind-$n.epoch"
  # Ten new links between particles 1024.. (the anchor set stays as it was), by their ids.
  python3 - "$work/$kind-$n.epoch/particles.ids" > "$work/$kind-$n.edits" <<'PY'
import random, sys
ids = open(sys.argv[1], "rb").read()
n = len(ids) // 32
r = random.Random(7)
for _ in range(10):
    a, b = r.randrange(1024, n), r.randrange(1024, n)
    print("add\t%s\t%s\t1" % (ids[32 * a:32 * a + 32].hex(), ids[32 * b:32 * b + 32].hex()))
PY
  "$r1" edit "$g" "$work/$kind-$n.edits" -o "$work/$kind-$n-next.graph" >/dev/null
  # shellcheck disable=SC2086
  rm -rf "$work/$kind-$n-next.epoch"
  # shellcheck disable=SC2086
  /usr/bin/time -f '%e' -o "$work/wall-$kind-$n-next" "$r1" epoch "$work/$kind-$n-next.graph" --from "$work/$kind-$n.epoch" $flags -q --no-field \
    --backend "$backend" -o "$work/$kind-$n-next.epoch"
  python3 - "$work/$kind-$n.epoch/manifest.json" "$work/$kind-$n-next.epoch/manifest.json" "$work/wall-$kind-$n" "$work/wall-$kind-$n-next" <<'PY'
import json, os, sys
full, inc = (json.load(open(p)) for p in sys.argv[1:3])
walls = [float(open(p).read().split()[-1]) if os.path.exists(p) else float("nan") for p in sys.argv[3:5]]
keys = ("read", "digest", "previous", "batch", "carry", "spectral", "certificate", "focus", "encoding", "hierarchy")
def row(m, name, region, wall):
    t = m["timings_s"]
    cols = [t.get(k, 0.0) for k in keys]
    print("%-9d %-7s %15s %7.2f %7.2f %6.2f %6.2f %6.2f %8.2f %6.2f %6.2f %8.2f %9.2f %8.2f %8.2f" % (
        m["snapshot"]["particles"], name, region, *cols, sum(t.values()), wall), end="")
tf = row(full, "full", "-", walls[0]); print()
u = inc["update"]
row(inc, "inc" if u["mode"] == "incremental" else "full*", "%d/%d" % (u["region"], u["rows"]), walls[1])
print(" %6.1f" % (walls[0] / walls[1]))
if u["mode"] != "incremental":
    print("          (solved in full: %s)" % u["reason"])
PY
  [ "${LINKS:-1}" = 2 ] || continue
  python3 - "$work/$kind-$n.epoch/particles.ids" 8 > "$work/$kind-$n.edits2" <<'PY'
import random, sys
ids = open(sys.argv[1], "rb").read()
n = len(ids) // 32
r = random.Random(int(sys.argv[2]))
for _ in range(10):
    a, b = r.randrange(1024, n), r.randrange(1024, n)
    print("add\t%s\t%s\t1" % (ids[32 * a:32 * a + 32].hex(), ids[32 * b:32 * b + 32].hex()))
PY
  "$r1" edit "$work/$kind-$n-next.graph" "$work/$kind-$n.edits2" -o "$work/$kind-$n-next2.graph" >/dev/null
  rm -rf "$work/$kind-$n-next2.epoch"
  # shellcheck disable=SC2086
  "$r1" epoch "$work/$kind-$n-next2.graph" --from "$work/$kind-$n-next.epoch" $flags -q --no-field --backend "$backend" -o "$work/$kind-$n-next2.epoch"
  python3 - "$work/$kind-$n-next2.epoch/manifest.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
t, u = m["timings_s"], m["update"]
ms = {k: 1000 * t.get(k, 0.0) for k in ("spectral", "certificate", "focus", "frame", "carry")}
print("%-9d inc2    %15s   update stages (ms): spectral %.2f, certificate %.2f, focus %.2f, frame %.2f, sum %.2f; carry %.2f" % (
    m["snapshot"]["particles"], "%d/%d" % (u["region"], u["rows"]), ms["spectral"], ms["certificate"], ms["focus"],
    ms["frame"], ms["spectral"] + ms["certificate"] + ms["focus"] + ms["frame"], ms["carry"]))
PY
done
