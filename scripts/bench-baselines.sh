#!/usr/bin/env bash
# Regenerates the leaderboard's results files (docs/bench/results/) and its report (docs/bench/).
# random: 10 runs (policy seeds 0-9) per mode; heuristic: 1 run per mode (deterministic);
# models/ppo-features.pt: 1 run on v0 (the mode it was trained on).
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python}
OUT=docs/bench/results
mkdir -p "$OUT"
for mode in v0 sticky-v0 full-v0; do
  for r in 0 1 2 3 4 5 6 7 8 9; do
    "$PY" -m chopperscape.bench evaluate random --mode "$mode" --policy-seed "$r" --out "$OUT/$mode.random.seed$r.json"
  done
  "$PY" -m chopperscape.bench evaluate heuristic --mode "$mode" --out "$OUT/$mode.heuristic.json"
done
"$PY" -m chopperscape.bench evaluate models/ppo-features.pt --mode v0 --out "$OUT/v0.ppo-features.json"
