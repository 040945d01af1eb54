#!/bin/bash
# SB3 PPO with the recipe's settings, 3 seeds x 15 M steps, each evaluated on the 100 held-out seeds.
s=$1
ROOT=$(pwd)
mkdir -p "${OUT:-runs/sb3}"
cd "${OUT:-runs/sb3}"  # run from the repository root: bash docs/curves/sb3-tuned-3seeds/run.sh K
PY=${PY:-$ROOT/.venv/bin/python}
[ -f seed-$s/model.zip ] || $PY "$ROOT/python/examples/sb3_ppo.py" --tuned --steps 15000000 --seed $s --out seed-$s > seed-$s.log 2>&1
[ -s seed-$s/eval.json ] || $PY -m chopperscape.learn.evaluate seed-$s/model.zip --episodes 100 --seed 1000000 --option obs_type=features > seed-$s/eval.json 2>> seed-$s.log
