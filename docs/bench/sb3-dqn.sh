#!/usr/bin/env bash
# The leaderboard's `SB3 DQN` rows: a stock Stable-Baselines3 DQN on the features at frame skip 4
# (python/examples/sb3_dqn.py: SB3's defaults but gamma 0.998, a 100,000-transition buffer, the recipe's MLP and
# VecNormalize on observations) trained on a mode's rules for STEPS decisions (default 1,000,000) with training
# seeds 0-9 (one env, reset seed SEED), one at a time, then each evaluated by the bench's protocol.
# Results: docs/bench/results/MODE.sb3-dqn.seedN.json (or $RESULTS/).
#     STEPS=1000000 bash docs/bench/sb3-dqn.sh MODE RUNS_DIR [SEEDS...]
set -euo pipefail
cd "$(dirname "$0")/../.."
PY=${PYTHON:-python}
mode=${1:?a mode: sticky-v0 or full-v0}; shift
runs=${1:?a folder for the runs}; shift
seeds=("${@:-0 1 2 3 4 5 6 7 8 9}")
steps=${STEPS:-1000000}
NAME="SB3 DQN, stock, $((steps / 1000)) k decisions"
for s in ${seeds[*]}; do
  "$PY" python/examples/sb3_dqn.py --mode "$mode" --steps "$steps" --seed "$s" --out "$runs/seed-$s"
  "$PY" -m chopperscape.bench evaluate "$runs/seed-$s/model.zip" --mode "$mode" --name "$NAME" \
    --option obs_type='"features"' --train-seeds "$s:1" \
    --out "${RESULTS:-docs/bench/results}/$mode.sb3-dqn.seed$s.json"
done
