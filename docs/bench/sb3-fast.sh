#!/usr/bin/env bash
# The leaderboard's `SB3 PPO` rows: Stable-Baselines3's PPO with the fast preset's settings (the same network,
# batch, epochs, gamma, GAE lambda, entropy, learning-rate schedule, observation and reward normalisation by
# VecNormalize, frame skip 4 and 3 M decisions; python/examples/sb3_ppo.py --preset fast) trained on a mode's rules
# with training seeds 0-9 (reset seeds SEED..SEED+127), one at a time, then each model evaluated by the bench's
# protocol on the features it was trained on. Results: docs/bench/results/MODE.sb3-ppo.seedN.json (or $RESULTS/).
#     bash docs/bench/sb3-fast.sh MODE RUNS_DIR [SEEDS...]
set -euo pipefail
cd "$(dirname "$0")/../.."
PY=${PYTHON:-python}
mode=${1:?a mode: sticky-v0 or full-v0}; shift
runs=${1:?a folder for the runs}; shift
seeds=("${@:-0 1 2 3 4 5 6 7 8 9}")
NAME="SB3 PPO, the fast preset's settings, 3 M decisions"
for s in ${seeds[*]}; do
  "$PY" python/examples/sb3_ppo.py --preset fast --mode "$mode" --seed "$s" --out "$runs/seed-$s"
  "$PY" -m chopperscape.bench evaluate "$runs/seed-$s/model.zip" --mode "$mode" --name "$NAME" \
    --option obs_type='"features"' --train-seeds "$s:128" \
    --out "${RESULTS:-docs/bench/results}/$mode.sb3-ppo.seed$s.json"
done
