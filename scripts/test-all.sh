#!/usr/bin/env bash
# Runs every test of the project: formatting, lints and the Rust tests of every crate, the fuzz smoke run; `play`
# in a real window under Xvfb; the Python package under pytest (installed from the x86_64 abi3 wheel, built once);
# the browser page in headless Chromium; that same wheel, the sdist and the documentation site as a user gets
# them (scripts/test-dist.sh). What only a release needs (the aarch64 and CLI wheels, the sdist's build, Python
# 3.9 and 3.13) is scripts/release-check.sh; docs/testing.md says what runs where.
# It first installs what the tests need (ffmpeg, Xvfb, xdotool, Chromium, the wasm target, wasm-bindgen-cli,
# Python venvs with the pinned packages of scripts/constraints.txt, npm packages); where it cannot (not root), a
# local run says what it skipped and why, and under CI=true that fails the run. Idempotent; quiet on success but
# for each runner's summary and, at the end, each part's wall time; never prompts (CI runs it with CI=true).
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"

log="$(mktemp)"
start=$SECONDS
failed=()
times=()
# CPU seconds (user + system) of this script's finished children and theirs: a part's CPU time barely changes when
# other work shares the machine, where its wall time does (fields 16 and 17 of /proc/PID/stat, in clock ticks).
tick=$(getconf CLK_TCK 2>/dev/null || echo 100)
cpu() { local st; read -r -a st <"/proc/$$/stat"; echo $(((st[15] + st[16]) / tick)); }
cpu_start=$(cpu)
# ffmpeg before the Rust tests: the CLI's .mp4 test checks real files when ffmpeg is there.
part_start=$SECONDS
part_cpu=$(cpu)
if ! { apt_install ffmpeg || skip "the .mp4 checks against ffmpeg (ffmpeg could not be installed)"; } 2>&1 \
  | tee -a "$log"; then
  failed+=("setup")
fi
# What the later parts install (apt packages, the wasm tools, npm and pip packages) is installed in the background
# while the Rust part builds: two jobs, one for the system and web tools, one for the Python venvs, so that the
# downloads overlap the compiler. Their output is shown if they fail (a part then tries its installs again itself).
prep_dir=$(mktemp -d)
trap 'rm -f "$log"; rm -rf "$prep_dir"' EXIT
(bash scripts/test-cli.sh --install-only && bash scripts/test-web.sh --install-only) >"$prep_dir/tools.log" 2>&1 &
prep_tools=$!
(bash scripts/test-python.sh --install-only && bash scripts/test-dist.sh --install-only) >"$prep_dir/venvs.log" 2>&1 &
prep_venvs=$!
times+=("setup $((SECONDS - part_start)) $(($(cpu) - part_cpu))")
for part in rust cli python web dist; do
  part_start=$SECONDS
  part_cpu=$(cpu)
  if [ "$part" = cli ]; then  # the installs, before the first part that needs them
    # In this shell, not a pipeline's subshell: only the shell that started a job can wait for it.
    for job in "tools:$prep_tools" "venvs:$prep_venvs"; do
      wait "${job#*:}" || { cat "$prep_dir/${job%%:*}.log"; say "the background installs (${job%%:*}) failed"; }
      grep -E '^(skipped|FAILED)' "$prep_dir/${job%%:*}.log" || true
    done >"$prep_dir/wait.log" 2>&1
    tee -a "$log" <"$prep_dir/wait.log"
    times+=("wait $((SECONDS - part_start)) $(($(cpu) - part_cpu))")
    part_start=$SECONDS
    part_cpu=$(cpu)
  fi
  bash "scripts/test-$part.sh" 2>&1 | tee -a "$log" || failed+=("$part")
  times+=("$part $((SECONDS - part_start)) $(($(cpu) - part_cpu))")
done

# The cost of each part, so that a slow part is seen the day it becomes slow (docs/testing.md keeps the table).
# "wait" is the time spent waiting for the background installs (their CPU time is counted there).
for t in "${times[@]}"; do
  read -r name wall cpu_s <<<"$t"
  printf 'time: %-6s %5d s wall %6d s CPU\n' "$name" "$wall" "$cpu_s"
done
printf 'time: %-6s %5d s wall %6d s CPU (%d min)\n' total $((SECONDS - start)) $(($(cpu) - cpu_start)) \
  $(((SECONDS - start + 59) / 60))
# What a local run could not check (CI=true fails instead), repeated here so that it is not lost in the output.
grep -E '^skipped: ' "$log" | sed 's/^/not checked here: /' || true

# One closing line for the whole run, summed from each runner's own summary lines.
# count LINES WHAT: the sum of the numbers in WHAT (e.g. "[0-9]+ passed") on the log lines matching LINES.
count() { { grep -E "$1" "$log" || true; } | { grep -oE "$2" || true; } | grep -oE '[0-9]+' | awk '{s+=$1} END {print s+0}'; }
cargo='^test result:'
pytest='^[0-9]+ (passed|failed)'
node='ℹ (pass|fail) [0-9]+'
passed=$(($(count "$cargo" '[0-9]+ passed') + $(count "$pytest" '[0-9]+ passed') + $(count "$node" 'pass [0-9]+')))
failures=$(($(count "$cargo" '[0-9]+ failed') + $(count "$pytest" '[0-9]+ failed') + $(count "$node" 'fail [0-9]+')))
passed=$((passed + $(grep -c '^play under Xvfb: ok' "$log" || true)))
if [ ${#failed[@]} -gt 0 ]; then
  say "FAILED: ${failed[*]} (see the output of scripts/test-<part>.sh above)"
  echo "$passed passed, $((failures > 0 ? failures : ${#failed[@]})) failed"
  exit 1
fi
echo "$passed passed, 0 failed"
