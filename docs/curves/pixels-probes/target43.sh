#!/usr/bin/env bash
# Issue 43's target protocol for one training seed: the candidate recipe (RECIPE below: the pixel preset, since the
# ninth session the grey bands, CoordConv and a second dense layer, `small-coord-deep-stem`, one epoch of 16
# minibatches at lr 2e-3, since the twelfth session the value loss at weight 1.0; with torch.compile, on both cores;
# the fifth session's `small-coord` candidate until the eighth) trained ALONE on the 2-core machine for its
# schedule (8 M decisions until the thirtieth session, 12 M since: 36-43 minutes alone on a 2-vCPU Zen 5 EPYC at
# about 5,000 decisions a second, about 100 on a Zen 3 one; `-- --steps 8000000` gives the old one), started in
# RUNS/seed-SEED or
# resumed from its checkpoint there; then the held-out evaluation (100 greedy episodes from seed 1,000,000, v0 rules
# at frame skip 4) of the model it has so far, written to RUNS/seed-SEED/eval-DECISIONS.json, and one line appended to
# RUNS/target.csv: seed, decisions, wall and CPU seconds of this call's training, the held-out mean, and how the
# episodes ended. Run nothing else meanwhile: the wall time is the claim (a run's numbers do not depend on the
# machine's load, its wall time does). A run folder lives on this machine only (runs/ is not committed): a seed cut by
# a session's end restarts from scratch in the next session, so start one only with more than its hour left.
#   bash docs/curves/pixels-probes/target43.sh SEED RUNS [MINUTES] [-- TRAINING_FLAGS...]
# TRAINING_FLAGS (after `--`) follow the recipe on a fresh start, so a candidate (`-- --steps 12000000`) runs by the
# same protocol; a resumed run takes its flags from its checkpoint, and flags given then are refused.
# The target: seeds 0-4 and 100-104, each under 60 minutes, IQM >= 7,000 on each set of five, none below 4,000.
# The body is one function, which bash reads whole before it runs: an edit of this file cannot change a call
# that is already running (bash reads a plain script as it goes); bash may then report a syntax error after `main`
# returns, its results already written (seen in the twelfth session).
main() {
  set -euo pipefail
  cd "$(dirname "$0")/../../.."
  PY=${PYTHON:-python}
  # The preset is the candidate since the ninth session (its learning settings; the eighth session's runs gave them
  # as flags: --network small-coord-deep-stem --learning-rate 2e-3 --update-epochs 1 --num-minibatches 16 --steps
  # 8000000, the same recipe field for field); the speed settings are the flags'.
  RECIPE=(--preset pixels --torch-compile --torch-threads 2)
  seed=${1:?a training seed}
  runs=${2:?a folder for the runs}
  shift 2
  minutes=60
  if [ $# -gt 0 ] && [ "$1" != -- ]; then
    minutes=$1
    shift
  fi
  if [ "${1:-}" = -- ]; then shift; fi
  local flags=("$@")
  out=$runs/seed-$seed
  mkdir -p "$runs"
  if [ -f "$out/resume.pt" ]; then
    if [ ${#flags[@]} -gt 0 ]; then
      echo "target43.sh: $out resumes with its checkpoint's recipe; training flags (${flags[*]}) are not allowed" >&2
      return 2
    fi
    cmd=("$PY" -m chopperscape.learn.train --resume "$out" --minutes "$minutes")
  else
    cmd=("$PY" -m chopperscape.learn.train "${RECIPE[@]}" "${flags[@]}" --seed "$seed" --minutes "$minutes"
      --out "$out")
  fi
  /usr/bin/time -f "%e %U %S" -o "$runs/.time-$seed" "${cmd[@]}" >/dev/null
  read -r wall user sys <"$runs/.time-$seed"
  decisions=$(tail -n 1 "$out/progress.csv" | cut -d, -f1)
  "$PY" -m chopperscape.learn.evaluate "$out/model.pt" --episodes 100 --seed 1000000 >"$out/eval-$decisions.json"
  [ -f "$runs/target.csv" ] || echo "seed,decisions,wall_s,cpu_s,mean_return,bird,fuel,truncated" >"$runs/target.csv"
  "$PY" - "$out/eval-$decisions.json" "$seed" "$decisions" "$wall" "$user" "$sys" >>"$runs/target.csv" <<'EOF'
import json, sys
path, seed, decisions, wall, user, system = sys.argv[1:]
e = json.load(open(path))
c = e.get("causes", {})
print(f"{seed},{decisions},{float(wall):.0f},{float(user) + float(system):.0f},{e['mean_return']:.1f},"
      f"{c.get('bird', 0):.2f},{c.get('fuel', 0):.2f},{c.get('truncated', 0):.2f}")
EOF
  rm -f "$runs/.time-$seed"  # only once its line is written: a cut evaluation leaves the call's seconds
  tail -n 1 "$runs/target.csv"
}
main "$@"
exit
