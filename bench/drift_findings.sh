#!/usr/bin/env bash
# The drift findings of the README (spec/drift.md, spec/incremental.md): `r1 drift` on the
# generator kinds and one real graph, small reweights and long-range additions, 8 epochs of one
# edit each with h = 2, summarised one row per run: epochs kept incremental, the certificates and
# true drifts of those epochs, the largest position drift against the full epoch (R_scene units),
# the focus L1 drift of the local focus update (largest over the incremental epochs), violations,
# and the reasons of the full solves. The real graph is Les Miserables' co-appearance network from
# NetworkX (python3-networkx; skipped with a line when it is absent).
# Usage: bench/drift_findings.sh [R1_BINARY] [WORK_DIR]
# DRIFT_FLAGS: extra `r1 drift` options (the README's second table: --keep-local); ONLY: the graphs
# to run, by name (lesmis rgg sbm ring grid ba crystal).
set -euo pipefail
r1=${1:-build/cli/r1}
work=${2:-$(mktemp -d)}
mkdir -p "$work"
flags=${DRIFT_FLAGS:-}
echo "r1 drift findings: $(nproc) cores, work dir $work, r1 drift --epochs 8 --batch 1 --hops 2 $flags"

graphs=()
gen() {  # NAME KIND ARGS...
  local name=$1
  shift
  [ -f "$work/$name.tsv" ] || "$r1" gen "$@" -o "$work/$name.tsv" >/dev/null
  graphs+=("$name")
}
if python3 -c 'import networkx' 2>/dev/null; then
  python3 - "$work/lesmis.tsv" <<'PY'
import sys, networkx as nx
g = nx.les_miserables_graph()
with open(sys.argv[1], "w") as f:
    for a, b, d in sorted(g.edges(data=True)):
        f.write("%s\t%s\t%g\n" % (a.replace(" ", "_"), b.replace(" ", "_"), d.get("weight", 1)))
PY
  graphs+=(lesmis)
else
  echo "Les Miserables skipped: python3-networkx is not installed"
fi
gen rgg rgg --n 3000
gen sbm sbm --n 2100 --k 4 --p-in 0.03 --p-out 0.0005
gen ring ring --n 2000
gen grid grid --dims 40x30
gen ba ba --n 3000 --m 3
gen crystal crystal

printf '%-8s %-9s %6s %5s %-13s %-13s %9s %9s %4s  %s\n' graph kind n inc certificate true_drift max_drift focus_l1 viol \
  "full because (first)"
for name in "${graphs[@]}"; do
  [ -z "${ONLY:-}" ] || [[ " $ONLY " == *" $name "* ]] || continue
  for kind in reweight add; do
    if [ "$kind" = reweight ]; then extra=(--kind reweight --scale 0.01); else extra=(--kind add --weight 0.01); fi
    out="$work/$name-$kind"
    rm -rf "$out"
    rc=0
    # shellcheck disable=SC2086
    "$r1" drift "$work/$name.tsv" --epochs 8 --batch 1 --hops 2 "${extra[@]}" $flags -o "$out" >"$out.log" 2>&1 || rc=$?
    if [ "$rc" -ne 0 ] && [ "$rc" -ne 4 ]; then
      echo "$name $kind: r1 drift exited $rc: $(tail -1 "$out.log")"
      continue
    fi
    python3 - "$out/drift.tsv" "$name" "$kind" "$out/drift.json" <<'PY'
import csv, json, sys
rows = list(csv.DictReader(open(sys.argv[1]), delimiter="\t"))
epochs = [r for r in rows if r["epoch"] != "0"]
inc = [r for r in epochs if r["mode"] == "incremental"]
def rng(key):
    v = [float(r[key]) for r in inc if r[key] not in ("-", "", "nan", "inf")]
    return "%.2g-%.2g" % (min(v), max(v)) if v else "-"
n = json.load(open(sys.argv[4]))["snapshot"]["particles"]
maxd = max((float(r["max_drift"]) for r in inc), default=0.0)
fl1 = max((float(r["focus_l1"]) for r in inc), default=0.0)
viol = sum(r["check"] == "VIOLATION" for r in epochs)
reasons = [r["reason"] for r in epochs if r["mode"] != "incremental"]
print("%-8s %-9s %6s %5s %-13s %-13s %9.2g %9.2g %4d  %s" % (
    sys.argv[2], sys.argv[3], n, "%d/%d" % (len(inc), len(epochs)), rng("certificate"), rng("true_drift"),
    maxd, fl1, viol, reasons[0][:60] if reasons else ""))
PY
  done
done
