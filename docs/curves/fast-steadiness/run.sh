#!/usr/bin/env bash
# The fast preset's steadiness on sticky-v0 (issue 44): train seed S of a variant and evaluate it by the bench's
# protocol (100 greedy episodes on the held-out seeds 1,000,000 onwards), its results file written here.
#   bash docs/curves/fast-steadiness/run.sh VARIANT SEEDS...     VARIANT: base | vf1
#   base: `--preset fast` as the leaderboard's `fast` row trains it (bench row fast --mode sticky-v0)
#   vf1:  the same with --vf-coef 1.0: the value loss weighted as SB3's PPO weighs it (vf_coef x MSE with
#         vf_coef 0.5, where the recipe's loss is vf_coef x 0.5 x MSE)
# Runs go to runs/fast-steadiness/VARIANT/seed-S (a seed with a results file here, or a model there, is not retrained).
set -euo pipefail
cd "$(dirname "$0")/../../.."
variant=$1
shift
case $variant in
  base) extra=() ;;
  vf1) extra=(--vf-coef 1.0) ;;
  *) echo "error: variant $variant: allowed base, vf1" >&2; exit 2 ;;
esac
py=${PYTHON:-.venv/bin/python}
mkdir -p "runs/fast-steadiness/$variant"
for s in "$@"; do
  out=runs/fast-steadiness/$variant/seed-$s
  res=docs/curves/fast-steadiness/$variant.seed$s.json
  [ -f "$res" ] && continue
  if [ ! -f "$out/model.pt" ]; then
    "$py" -m chopperscape.learn.train --preset fast --mode sticky-v0 --steps 3000000 --seed "$s" --out "$out" \
      --force "${extra[@]}" >"$out.log" 2>&1 || { echo "seed $s failed: $out.log" >&2; exit 1; }
  fi
  "$py" -m chopperscape.bench evaluate "$out/model.pt" --mode sticky-v0 \
    --name "fast preset ($variant), 3 M decisions" --out "$res"
  cp "$out/progress.csv" "docs/curves/fast-steadiness/$variant.seed$s.csv"
done
