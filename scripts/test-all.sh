#!/usr/bin/env bash
# Runs every test of the project: formatting, lints and the Rust tests of every crate; `play` in a real window
# under Xvfb; the Python package under pytest; the browser page in headless Chromium; the wheels, the sdist and
# the documentation site as a user gets them (scripts/test-dist.sh).
# It first installs what the tests need (ffmpeg, Xvfb, xdotool, Chromium, the wasm target, wasm-bindgen-cli,
# a Python venv with the package and its test dependencies, npm packages); where it cannot (not root), it says
# what it skipped and why. Idempotent; quiet on success; never prompts (CI runs it with CI=true).
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"

# ffmpeg before the Rust tests: the CLI's .mp4 test checks real files when ffmpeg is there.
apt_install ffmpeg || true

log="$(mktemp)"
trap 'rm -f "$log"' EXIT
failed=()
for part in rust cli python web dist; do
  bash "scripts/test-$part.sh" 2>&1 | tee -a "$log" || failed+=("$part")
done

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
