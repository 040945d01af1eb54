#!/usr/bin/env bash
# Runs every test of the project: formatting, lints and the Rust tests of every crate; `play` in a real window
# under Xvfb; the Python package under pytest; the browser page in headless Chromium.
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
for part in rust cli python web; do
  bash "scripts/test-$part.sh" 2>&1 | tee -a "$log" || failed+=("$part")
done

# One closing line for the whole run, summed from each runner's own summary lines.
passed=$(grep -oE '^test result: [a-zA-Z]+\. [0-9]+ passed' "$log" | grep -oE '[0-9]+ passed' | awk '{s+=$1} END {print s+0}')
fails=$(grep -oE '^test result: [a-zA-Z]+\. [0-9]+ passed; [0-9]+ failed' "$log" | grep -oE '[0-9]+ failed' | awk '{s+=$1} END {print s+0}')
py_passed=$(grep -oE '^[0-9]+ passed' "$log" | awk '{s+=$1} END {print s+0}')
py_failed=$(grep -oE '^[0-9]+ failed|, [0-9]+ failed' "$log" | grep -oE '[0-9]+' | awk '{s+=$1} END {print s+0}')
web_passed=$(grep -oE 'ℹ pass [0-9]+' "$log" | grep -oE '[0-9]+' | awk '{s+=$1} END {print s+0}')
web_failed=$(grep -oE 'ℹ fail [0-9]+' "$log" | grep -oE '[0-9]+' | awk '{s+=$1} END {print s+0}')
window=$(grep -c '^play under Xvfb: ok' "$log" || true)
total_passed=$((passed + py_passed + web_passed + window))
total_failed=$((fails + py_failed + web_failed + ${#failed[@]}))
if [ ${#failed[@]} -gt 0 ]; then
  say "FAILED: ${failed[*]} (see the output of scripts/test-<part>.sh above)"
  echo "$total_passed passed, $total_failed failed"
  exit 1
fi
echo "$total_passed passed, 0 failed"
