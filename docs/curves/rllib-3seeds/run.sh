#!/bin/bash
# RLlib PPO with the recipe's settings (γ 0.9995, entropy 0.02, batches of 16,384 steps in minibatches of 2,048,
# 4 epochs, lr 3e-4 falling linearly to 0, returns scaled; RLlib's own clip 0.3 and KL penalty), 5 M env steps,
# then 100 greedy episodes on the held-out seeds 1000000.. . From the repository root: bash docs/curves/rllib-3seeds/run.sh K   (K: training seed)
# The committed figures (docs/curves/rllib-3seeds): seed 0 was trained without the --eval flags, then evaluated
# from its checkpoint with `--restore runs/rllib-3seeds/ckpt-seed-0 --eval-only --eval-episodes 100` (the same
# figures as in-run evaluation: test_rllib checks that a restored checkpoint plays identically); seeds 1 and 2 ran
# this script as it then stood: their ReturnScaling restarted the discounted return at each batch's chunk of an
# episode, which it no longer does, so today's runs differ from the committed ones.
# The summary: python -m chopperscape.learn.seeds --summarise DIR --steps 5000000
s=$1
OUT=${OUT:-runs/rllib-3seeds}
mkdir -p "$OUT"
PY=${PY:-.venv-rllib/bin/python}
[ -s "$OUT/seed-$s.eval.json" ] || OMP_NUM_THREADS=1 $PY python/examples/rllib_ppo.py --steps 5000000 --seed "$s" \
  --env-runners 1 --envs-per-runner 64 --train-batch-size 16384 --minibatch-size 2048 --epochs 4 \
  --gamma 0.9995 --entropy 0.02 --lr-floor 0 --csv "$OUT/seed-$s.csv" --checkpoint "$OUT/ckpt-seed-$s" \
  --summary "$OUT/seed-$s.summary.json" --eval-episodes 100 --eval-seed 1000000 --eval-out "$OUT/seed-$s.eval.json" \
  > "$OUT/seed-$s.log" 2>&1
