#!/usr/bin/env bash
# The leaderboard's trained rows (docs/site/bench.md): ROW trained on MODE's rules with training seeds 0-9 (or
# SEEDS), one at a time, then each model evaluated by the bench's protocol under the row's name. Results:
# docs/bench/results/MODE.ROW.seedN.json (or $RESULTS/). MODE is sticky-v0 or full-v0 (frame skip 4).
#   fast     the fast preset, `train --preset fast --mode MODE`: about 2 CPU minutes a seed to train, 1 to evaluate
#   features the features recipe as it stands (no preset), `train --mode MODE --steps $STEPS` (default 3,000,000
#            decisions, the fast preset's budget)
#   sb3-ppo  SB3's PPO with the fast preset's settings, `python/examples/sb3_ppo.py --preset fast`: about as long
#   sb3-dqn  a stock SB3 DQN, `python/examples/sb3_dqn.py`, for $STEPS decisions (default 500,000: about 12
#            minutes of one core a seed; its training return is flat from there to 800,000)
#   pixels   the pixel preset on frames alone, `train --preset pixels --mode MODE --steps $STEPS` (default
#            1,000,000 decisions: about 17 minutes of one core a seed); a seed's run resumes from its checkpoint
#   rllib-ppo  RLlib's PPO with the fast preset's settings, `python/examples/rllib_ppo.py` (one runner of 128 games,
#            run by $RLLIB_PYTHON, default .venv-rllib/bin/python), exported with --export and evaluated from the ONNX
# A seed whose results file exists is skipped, so a long row continues where it stopped, and so is a seed another
# rows.sh is training (its claim, RUNS_DIR/seed-S.claim, holds a live process id): several rows.sh on one row share
# its seeds, one process a core; a claim is removed when its seed ends, the script fails or is stopped. SEEDS are
# numbers and ranges (3, 0-9; 0-9 by default), nothing else. DRY_RUN=1 prints each command (shell-quoted, one a
# line) instead of running it.
#     bash docs/bench/rows.sh ROW MODE RUNS_DIR [SEEDS...]
set -euo pipefail
cd "$(dirname "$0")/../.."
PY=${PYTHON:-python}
row=${1:?a row: fast, features, sb3-ppo, sb3-dqn, rllib-ppo or pixels}
mode=${2:?a mode: sticky-v0 or full-v0}
runs=${3:?a folder for the runs}
shift 3
# The seeds: numbers and ranges only, read as text (never a shell pattern: '*' is refused, not a file list).
seeds=()
for arg in "${@:-0-9}"; do
  read -r -a items <<<"$arg"
  for item in "${items[@]}"; do
    if [[ ! $item =~ ^([0-9]{1,9})(-([0-9]{1,9}))?$ ]]; then
      echo "error: seed '$item': allowed a number or a range FIRST-LAST (e.g. 3 or 0-9)" >&2
      exit 2
    fi
    lo=$((10#${BASH_REMATCH[1]}))
    hi=$((10#${BASH_REMATCH[3]:-${BASH_REMATCH[1]}}))
    if ((hi < lo || hi - lo >= 1000)); then
      echo "error: seeds '$item': allowed FIRST-LAST with FIRST <= LAST, at most 1000 seeds" >&2
      exit 2
    fi
    for ((s = lo; s <= hi; s++)); do
      [[ " ${seeds[*]} " == *" $s "* ]] || seeds+=("$s")
    done
  done
done
steps=${STEPS:-}
# claim FILE: takes a seed for this process (the claim holds its process id), unless a live process holds it.
claim() {
  if (set -o noclobber; echo $$ >"$1") 2>/dev/null; then return 0; fi
  local holder; holder=$(cat "$1" 2>/dev/null || true)
  if [ -n "$holder" ] && kill -0 "$holder" 2>/dev/null; then return 1; fi
  rm -f "$1"  # its process is gone: a stopped run, whose seed starts again (a pixel run resumes)
  (set -o noclobber; echo $$ >"$1") 2>/dev/null
}
# The claim this process holds, removed when its seed ends, and when the script fails or is stopped.
claimed=""
release() { if [ -n "$claimed" ]; then rm -f "$claimed"; claimed=""; fi; }
trap release EXIT
trap 'release; exit 130' INT
trap 'release; exit 143' TERM
# run CMD...: runs it (quietly: its standard output dropped), or prints it under DRY_RUN.
run() { if [ -n "${DRY_RUN:-}" ]; then local line; line=$(printf '%q ' "$@"); echo "${line% }"; else "$@"; fi; }
quietly() { if [ -n "${DRY_RUN:-}" ]; then run "$@"; else "$@" >/dev/null; fi; }
# A budget as a row's name says it: 3000000 is "3 M", 250000 "250 k".
budget() { if (($1 % 1000000 == 0)); then echo "$(($1 / 1000000)) M"; else echo "$(($1 / 1000)) k"; fi; }
case $row in
  fast) name="fast preset: PPO on features, 3 M decisions" ;;
  features) steps=${steps:-3000000}; name="features recipe: PPO on features, $(budget "$steps") decisions" ;;
  sb3-ppo) name="SB3 PPO, the fast preset's settings, 3 M decisions" ;;
  sb3-dqn) steps=${steps:-500000}; name="SB3 DQN, stock, $(budget "$steps") decisions" ;;
  rllib-ppo) name="RLlib PPO, the fast preset's settings, 3 M decisions" ;;
  pixels) steps=${steps:-1000000}; name="pixel preset: PPO on 42x42 frames alone, $(budget "$steps") decisions" ;;
  *) echo "error: unknown row '$row': allowed fast, features, sb3-ppo, sb3-dqn, rllib-ppo, pixels" >&2; exit 2 ;;
esac
case $mode in
  sticky-v0 | full-v0) ;;
  *) echo "error: unknown mode '$mode' for a trained row: allowed sticky-v0, full-v0 (frame skip 4)" >&2; exit 2 ;;
esac
for s in "${seeds[@]}"; do
  out=$runs/seed-$s
  results=${RESULTS:-docs/bench/results}/$mode.$row.seed$s.json
  if [ -f "$results" ]; then
    echo "$results exists: seed $s skipped"
    continue
  fi
  if [ -z "${DRY_RUN:-}" ]; then
    mkdir -p "$runs"
    if ! claim "$runs/seed-$s.claim"; then
      echo "seed $s is being trained by process $(cat "$runs/seed-$s.claim"): skipped"
      continue
    fi
    claimed=$runs/seed-$s.claim
  fi
  case $row in
    fast)
      quietly "$PY" -m chopperscape.learn.train --preset fast --mode "$mode" --seed "$s" --out "$out" --force
      model=$out/model.pt; given=() ;;
    features)
      quietly "$PY" -m chopperscape.learn.train --mode "$mode" --steps "$steps" --seed "$s" --out "$out" --force
      model=$out/model.pt; given=() ;;
    sb3-ppo)
      run "$PY" python/examples/sb3_ppo.py --preset fast --mode "$mode" --seed "$s" --out "$out"
      model=$out/model.zip; given=(--option obs_type='"features"' --train-seeds "$s:128") ;;
    sb3-dqn)
      run "$PY" python/examples/sb3_dqn.py --mode "$mode" --steps "$steps" --seed "$s" --out "$out"
      model=$out/model.zip; given=(--option obs_type='"features"' --train-seeds "$s:1") ;;
    rllib-ppo)
      # The fast preset's settings in RLlib's terms (rllib_ppo.py --preset fast reads them from PRESETS).
      run mkdir -p "$out"
      quietly "${RLLIB_PYTHON:-.venv-rllib/bin/python}" python/examples/rllib_ppo.py --preset fast --env-runners 1 \
        --seed "$s" --env-config "{\"mode\": \"$mode\"}" --csv "$out/progress.csv" --summary "$out/summary.json" \
        --export "$out/model.onnx"
      model=$out/model.onnx; given=() ;;
    pixels)
      if [ -f "$out/resume.pt" ]; then
        quietly "$PY" -m chopperscape.learn.train --resume "$out"
      else
        quietly "$PY" -m chopperscape.learn.train --preset pixels --mode "$mode" --steps "$steps" --seed "$s" \
          --out "$out"
      fi
      model=$out/model.pt; given=() ;;
  esac
  run "$PY" -m chopperscape.bench evaluate "$model" --mode "$mode" --name "$name" "${given[@]}" \
    --out "$results"
  release
done
