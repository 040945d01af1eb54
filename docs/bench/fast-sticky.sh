#!/usr/bin/env bash
# The leaderboard's `fast` rows on sticky-v0: the fast preset (docs/learning.md, "Learning in minutes") trained on
# the rung's rules (frame skip 4, sticky actions 0.25) with training seeds 0-9, one at a time, then each model
# evaluated by the bench's protocol. Results: docs/bench/results/sticky-v0.fast.seedN.json (or $RESULTS/). About 2
# CPU minutes of training and 1 of evaluation a seed on the project's 2-core VM.
#     bash docs/bench/fast-sticky.sh RUNS_DIR [SEEDS...]
set -euo pipefail
cd "$(dirname "$0")/../.."
PY=${PYTHON:-python}
runs=${1:?a folder for the runs}; shift
seeds=("${@:-0 1 2 3 4 5 6 7 8 9}")
for s in ${seeds[*]}; do
  "$PY" -m chopperscape.learn.train --preset fast --option sticky_prob=0.25 --seed "$s" --out "$runs/seed-$s" --force >/dev/null
  "$PY" -m chopperscape.bench evaluate "$runs/seed-$s/model.pt" --mode sticky-v0 \
    --out "${RESULTS:-docs/bench/results}/sticky-v0.fast.seed$s.json"
done
