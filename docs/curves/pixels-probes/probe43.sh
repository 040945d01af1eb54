#!/usr/bin/env bash
# One probe of issue 43: `--preset pixels` (the target's recipe) with FLAGS, on each training seed side by side, one
# thread each (the 2-core machine's two seeds at once), compiled, to UNTIL decisions on the preset's 8 M schedule
# (so that a change of the schedule's end, such as `--lr-floor`, is compared where it acts: UNTIL 8000000). Each seed
# trains into RUNS/NAME-seedS, or resumes there; then its held-out evaluation (the target's protocol: 100 greedy
# episodes from seed 1,000,000) and its curve, recipe and evaluation copied beside this script as
# p43-NAME-seedS.{csv,recipe.json,eval.json}, for `compare.py` against the target's `p43-target-stem8m-seed*.csv`
# (the same seeds' curves: the same recipe but for FLAGS, and the same decisions, on two threads).
#   bash docs/curves/pixels-probes/probe43.sh NAME UNTIL RUNS SEED [SEED ...] -- [FLAG ...]
# e.g. bash docs/curves/pixels-probes/probe43.sh floor30 8000000 runs/probes 0 3 -- --lr-floor 0.3
# A run folder lives on this machine only: a probe cut by a session's end restarts in the next one.
# The body is one function, which bash reads whole before it runs: an edit cannot reach a running call.
main() {
  set -euo pipefail
  cd "$(dirname "$0")/../../.."
  local here=docs/curves/pixels-probes PY=${PYTHON:-python}
  local name=${1:?a probe name} until=${2:?decisions to train to} runs=${3:?a folder for the runs}
  shift 3
  local seeds=()
  while [ $# -gt 0 ] && [ "$1" != -- ]; do
    seeds+=("$1")
    shift
  done
  [ "${1:-}" = -- ] && shift
  [ ${#seeds[@]} -gt 0 ] || { echo "probe43.sh: no training seed given" >&2; return 2; }
  mkdir -p "$runs"
  local pids=() seed out
  for seed in "${seeds[@]}"; do
    out=$runs/$name-seed$seed
    if [ -f "$out/resume.pt" ]; then
      "$PY" -m chopperscape.learn.train --resume "$out" --until "$until" >"$out.log" 2>&1 &
    else
      "$PY" -m chopperscape.learn.train --preset pixels --torch-compile --torch-threads 1 "$@" --seed "$seed" \
        --until "$until" --out "$out" >"$out.log" 2>&1 &
    fi
    pids+=($!)
  done
  local failed=0 pid
  for pid in "${pids[@]}"; do wait "$pid" || failed=1; done
  [ $failed = 0 ] || { echo "probe43.sh: a training failed (see $runs/$name-seed*.log)" >&2; return 1; }
  for seed in "${seeds[@]}"; do
    out=$runs/$name-seed$seed
    "$PY" -m chopperscape.learn.evaluate "$out/model.pt" --episodes 100 --seed 1000000 >"$out/eval.json"
    cp "$out/progress.csv" "$here/p43-$name-seed$seed.csv"
    cp "$out/recipe.json" "$here/p43-$name-seed$seed.recipe.json"
    cp "$out/eval.json" "$here/p43-$name-seed$seed.eval.json"
    echo "seed $seed: $(tail -n 1 "$out/progress.csv" | cut -d, -f1) decisions, held out $("$PY" -c \
      'import json, sys; print(json.load(open(sys.argv[1]))["mean_return"])' "$out/eval.json")"
  done
}
main "$@"
exit
