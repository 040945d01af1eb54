#!/usr/bin/env bash
# One RLlib difference probed on the leaderboard's rllib-ppo row (issue 44): seed S of the row on MODE, trained with
# the row's exact command (its `training.json`, from `bench row rllib-ppo`) plus FLAGS, evaluated by the bench's
# protocol into docs/curves/rllib-bench-probes/NAME/MODE.seedS.json (its curve beside it).
#   bash docs/curves/rllib-bench-probes/probe.sh NAME MODE "SEEDS" FLAGS...
#   e.g. bash docs/curves/rllib-bench-probes/probe.sh adam-eps-1e-5 full-v0 "0 1" --adam-eps 1e-5
# The row's run folders are read from RUNS (default runs/bench-rllib/MODE, where `bench row` trained them); the
# probe's runs go to runs/rllib-probes/NAME/MODE/seed-S.
set -euo pipefail
cd "$(dirname "$0")/../../.."
name=$1 mode=$2 seeds=$3
shift 3
py=${PYTHON:-.venv/bin/python}
runs=${RUNS:-runs/bench-rllib/$mode}
out_dir=docs/curves/rllib-bench-probes/$name
mkdir -p "$out_dir"
for s in $seeds; do
  res=$out_dir/$mode.seed$s.json
  [ -f "$res" ] && continue
  run=runs/rllib-probes/$name/$mode/seed-$s
  mkdir -p "$run"
  if [ ! -f "$run/model.onnx" ]; then
    # The row's command with this run's files and the probe's flags.
    mapfile -t cmd < <("$py" - "$runs/seed-$s/training.json" "$run" "$@" <<'PY'
import json, sys
record, run, extra = sys.argv[1], sys.argv[2], sys.argv[3:]
command = json.load(open(record))["command"]
files = {"--csv": "progress.csv", "--summary": "summary.json", "--export": "model.onnx"}
out = [f"{a.split('=')[0]}={run}/{files[a.split('=')[0]]}" if a.split("=")[0] in files else a for a in command]
print("\n".join(out + extra))
PY
)
    RAY_worker_niceness=0 "${cmd[@]}" >"$run.log" 2>&1 || { echo "seed $s failed: $run.log" >&2; exit 1; }
  fi
  "$py" -m chopperscape.bench evaluate "$run/model.onnx" --mode "$mode" \
    --name "RLlib PPO probe $name, 3 M decisions" --out "$res"
  cp "$run/progress.csv" "$out_dir/$mode.seed$s.csv"
done
