#!/usr/bin/env bash
# The Rust learner beside torch's, side by side (a benchmark, not a test; docs/rust-learner.md): the fast preset,
# seed 0, 200,000 decisions each, one run after the other under /usr/bin/time; prints each run's wall and CPU
# seconds and the last progress row (env_steps, wall_s: the training loop's own seconds).
#   scripts/bench-learn.sh                      # rust at 1 and 2 threads, then torch
#   RUNS="torch rust1" scripts/bench-learn.sh   # another order
# Needs target/release/chopperscape (cargo build --release -p chopperscape-cli) and a Python with torch (PYTHON,
# default .venv/bin/python) that imports this checkout's package (PYTHONPATH=python with its _core built).
set -u
cd "$(dirname "$0")/.."
B=target/release/chopperscape
PY=${PYTHON:-.venv/bin/python}
tmp=$(mktemp -d)
for run in ${RUNS:-rust1 rust2 torch}; do
  case $run in
    rust1) cmd="$B train --preset fast --seed 0 --out $tmp/$run --steps 200000 --threads 1" ;;
    rust2) cmd="$B train --preset fast --seed 0 --out $tmp/$run --steps 200000 --threads 2" ;;
    torch) cmd="$PY -m chopperscape.learn.train --preset fast --seed 0 --out $tmp/$run --steps 200000" ;;
    *) echo "unknown run $run (rust1, rust2, torch)" >&2; exit 2 ;;
  esac
  echo "== $run: $cmd  (load $(cut -d' ' -f1-3 /proc/loadavg))"
  /usr/bin/time -f "$run process: wall %e s, user %U s, sys %S s" $cmd >/dev/null 2>"$tmp/$run.err"
  tail -1 "$tmp/$run.err"
  echo "$run last row: $(tail -1 "$tmp/$run/progress.csv" | cut -d, -f1-4)"
done
rm -rf "$tmp"
