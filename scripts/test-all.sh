#!/usr/bin/env bash
# Runs every test of the project: Rust, then the command line under Xvfb, Python, and the browser.
# Installs what the tests need (Python venv and packages, Xvfb, ffmpeg, Chromium, the wasm target) first.
# Idempotent; quiet on success. With CI=true it never prompts.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"
for part in rust cli python web; do
  script="scripts/test-$part.sh"
  [ -f "$script" ] || continue
  bash "$script"
done
