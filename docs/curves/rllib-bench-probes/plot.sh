#!/usr/bin/env bash
# RLlib PPO on sticky-v0, training seed 0, 3 M decisions, the fast preset's settings (`bench row rllib-ppo`), as the
# example changed this session, beside the features recipe's seed 0 (`bench row features`): training return (last 100
# episodes) by decisions. From the repository root: bash docs/curves/rllib-bench-probes/plot.sh
#   a: RLlib's clip 0.3 and adaptive KL penalty, rewards scaled by returns restarted at each 128-step chunk
#   b: the preset's clip 0.2, no KL penalty, returns still restarted per chunk
#   c: as b, with ReturnScaling's return carried over the whole episode (the leaderboard's row)
# Each *.results.json is the run's `bench evaluate` (100 held-out episodes, greedy).
set -euo pipefail
d=docs/curves/rllib-bench-probes
${PYTHON:-python} -m chopperscape.learn.plot "$d/a-kl-clip03-chunk-returns.csv" "$d/b-clip02-chunk-returns.csv" \
  "$d/c-clip02-episode-returns.csv" "$d/features-recipe.csv" \
  --label "RLlib: clip 0.3 + KL penalty, chunk returns (held out 5,238)" \
  --label "RLlib: clip 0.2, chunk returns (held out 2,633)" \
  --label "RLlib: clip 0.2, episode returns (held out 3,330)" \
  --label "features recipe (held out 8,991)" \
  --title "sticky-v0, training seed 0: RLlib PPO with the fast preset's settings, three ways, and the features recipe" \
  --out "$d/curves.png"
