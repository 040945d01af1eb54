#!/usr/bin/env bash
# The teacher-free target's runs (issue 28): the pixel preset until the ninth session (p3 of docs/notes/teacher-free-probes-second-round.md:
# the 42x42 agent view, GAE lambda 0.98, 64 envs x 128 steps, 2 epochs at lr 1e-3, a 10 M decision schedule; seeds 0-2
# were started with those settings as flags, the same recipe) for training seed SEED, started in RUNS/seed-SEED or
# resumed from its checkpoint there, for at most MINUTES of wall time this
# call; then the held-out evaluation of the model it has so far (RUNS/seed-SEED/eval-DECISIONS.json: 100 greedy
# episodes from seed 1,000,000, its frame skip 4).
#   bash docs/curves/pixels-probes/target.sh SEED RUNS MINUTES
set -euo pipefail
cd "$(dirname "$0")/../../.."
PY=${PYTHON:-python}
seed=${1:?a training seed}
runs=${2:?a folder for the runs}
minutes=${3:?the most minutes of wall time for this call}
out=$runs/seed-$seed
if [ -f "$out/resume.pt" ]; then
  "$PY" -m chopperscape.learn.train --resume "$out" --minutes "$minutes" >/dev/null
else
  # The preset as it was until the ninth session (the flags give its settings back; test_train.py checks them).
  "$PY" -m chopperscape.learn.train --preset pixels --network small --update-epochs 2 --num-minibatches 4 \
    --learning-rate 1e-3 --steps 10000000 --seed "$seed" --minutes "$minutes" --out "$out" >/dev/null
fi
decisions=$(tail -n 1 "$out/progress.csv" | cut -d, -f1)
"$PY" -m chopperscape.learn.evaluate "$out/model.pt" --episodes 100 --seed 1000000 >"$out/eval-$decisions.json"
cat "$out/eval-$decisions.json"
