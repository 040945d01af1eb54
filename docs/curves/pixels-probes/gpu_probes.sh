#!/bin/bash
# Teacher-free pixel probes, eight at once on one GPU machine (16 cores): each probe is the `pixels` preset
# (frame skip 4, 4 stacked grayscale frames, the small CNN, no teacher, no auxiliary loss) with one change,
# trained for MINUTES of wall time on a 10 M-decision schedule, so that every probe is the prefix of the same
# schedule and curves compare at equal decisions. Usage (from the repository root, chopperscape installed):
#     bash docs/curves/pixels-probes/gpu_probes.sh OUT [MINUTES] [DEVICE]
# The curves of the run of 2026-11-25 (an H200 machine lent for 15 minutes) are in docs/curves/pixels-probes/.
set -u
out=${1:?OUT folder}; minutes=${2:-7}; device=${3:-cuda}
mkdir -p "$out"
base=(--preset pixels --steps 10000000 --minutes "$minutes" --device "$device" --torch-threads 1)
declare -A probes=(
  [tf-84]=""
  [tf-84-shift]="--augment shift"
  [tf-42]="--option obs_size=[42,42]"
  [tf-42-shift]="--option obs_size=[42,42] --augment shift"
  [tf-84-lam98]="--gae-lambda 0.98"
  [tf-84-e64-lr5e-4]="--num-envs 64 --learning-rate 5e-4 --update-epochs 2"
  [tf-84-art]="--option look=\"art\""
  [tf-42-art]="--option obs_size=[42,42] --option look=\"art\""
)
for name in "${!probes[@]}"; do
  # shellcheck disable=SC2086 # the probe's flags are words
  eval "${PYTHON:-python3}" -m chopperscape.learn.train "${base[@]}" --out "$out/$name" ${probes[$name]} >"$out/$name.log" 2>&1 &
done
wait
for name in "${!probes[@]}"; do
  echo "== $name: $(tail -1 "$out/$name/progress.csv" | cut -d, -f1-6)"
  tail -2 "$out/$name.log"
done
