#!/usr/bin/env bash
# Issue 43's optional GPU figure: `--preset pixels-large --device cuda` (the pixel preset with 256 envs and 8
# minibatches of 4,096 samples), one run alone on a GPU machine, for MINUTES of wall time on the preset's schedule
# (28 M decisions since the fourteenth session, about 6 minutes on an H200 with 12 env threads; 8 M before); then
# the held-out evaluation of the model it reached (100 greedy episodes from seed 1,000,000, v0 rules at frame skip
# 4, as the target's protocol). Decisions a second and minutes to a training return of 7,000 are read from
# OUT/run/progress.csv (`wall_s` beside `env_steps` and `mean_return`).
#   [PRESET=pixels] [FLAGS="--steps 32000000"] bash docs/curves/pixels-probes/gpu_large.sh OUT [MINUTES] [SEED] \
#       [ENV_THREADS] [--no-torch-compile]
# (PRESET: another preset in place of pixels-large, on the same GPU and flags; FLAGS: more training flags, split on
# spaces, e.g. a longer schedule.) The evaluation is cut after EVAL_SECONDS (default 240) so that a lease's command
# ends in its limit; OUT/run/model.pt can then be evaluated elsewhere by the same command.
# The speed flags are the machine's: torch.compile, and env threads for its cores (a speed setting: the native
# vector env gives the same frames for any thread count). chopperscape must be importable (the lent machine of
# 2026-11-28 had torch but neither chopperscape nor gymnasium: the session carried their wheels, see the notes).
main() {
  set -euo pipefail
  out=${1:?an output folder}
  minutes=${2:-8}
  seed=${3:-0}
  threads=${4:-8}
  compile=${5:---torch-compile}
  PY=${PYTHON:-python3}
  mkdir -p "$out"
  nvidia-smi --query-gpu=name,memory.total --format=csv,noheader >"$out/machine.txt" 2>&1 || true
  echo "$(nproc) CPUs: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2)" >>"$out/machine.txt"
  /usr/bin/time -f "%e %U %S" -o "$out/time.txt" "$PY" -m chopperscape.learn.train --preset "${PRESET:-pixels-large}" \
    --device cuda "$compile" --env-threads "$threads" --torch-threads 4 --seed "$seed" --minutes "$minutes" \
    --out "$out/run" ${FLAGS:-} >"$out/train.log" 2>&1
  decisions=$(tail -n 1 "$out/run/progress.csv" | cut -d, -f1)
  local limit=${EVAL_SECONDS:-240} rc=0
  timeout "$limit" "$PY" -m chopperscape.learn.evaluate "$out/run/model.pt" --episodes 100 --seed 1000000 \
    >"$out/eval-$decisions.json" || rc=$?
  if [ $rc = 124 ]; then
    echo "evaluation cut after $limit s" >&2
  elif [ $rc != 0 ]; then
    echo "evaluation failed ($rc)" >&2
  fi
  "$PY" - "$out/run/progress.csv" <<'EOF'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
last = rows[-1]
print(f"decisions {last['env_steps']} in {float(last['wall_s']):.0f} s: "
      f"{int(last['env_steps']) / float(last['wall_s']):.0f} decisions/s; training return {last['mean_return']}")
hit = next((r for r in rows if float(r["mean_return"] or 0) >= 7000), None)
print("training return 7,000 first at", (hit["env_steps"], hit["wall_s"]) if hit else "not reached")
EOF
  cat "$out/time.txt" "$out/eval-$decisions.json"
}
main "$@"
exit
