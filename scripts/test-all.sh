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

failed=()
for part in rust cli python web; do
  bash "scripts/test-$part.sh" || failed+=("$part")
done
if [ ${#failed[@]} -gt 0 ]; then
  say "FAILED: ${failed[*]} (see the output of scripts/test-<part>.sh above)"
  exit 1
fi
echo "all tests passed: rust, cli, python, web"
