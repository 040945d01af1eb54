#!/usr/bin/env bash
# The leaderboard's `fast` rows: the fast preset (docs/learning.md, "Learning in minutes") trained on a mode's rules
# (`train --mode MODE`; sticky-v0 and full-v0, whose frame skip 4 is the preset's) with training seeds 0-9, one at
# a time, then each model evaluated by the bench's protocol. Results: docs/bench/results/MODE.fast.seedN.json (or
# $RESULTS/). About 2 CPU minutes of training and 1 of evaluation a seed on the project's 2-core VM.
#     bash docs/bench/fast.sh MODE RUNS_DIR [SEEDS...]
set -euo pipefail
cd "$(dirname "$0")/../.."
PY=${PYTHON:-python}
mode=${1:?a mode: sticky-v0 or full-v0}; shift
runs=${1:?a folder for the runs}; shift
seeds=("${@:-0 1 2 3 4 5 6 7 8 9}")
NAME="fast preset: PPO on features, 3 M decisions"
for s in ${seeds[*]}; do
  "$PY" -m chopperscape.learn.train --preset fast --mode "$mode" --seed "$s" --out "$runs/seed-$s" --force >/dev/null
  "$PY" -m chopperscape.bench evaluate "$runs/seed-$s/model.pt" --mode "$mode" --name "$NAME" \
    --out "${RESULTS:-docs/bench/results}/$mode.fast.seed$s.json"
done
