#!/usr/bin/env bash
# Formatting, lints, the Rust tests of every crate (unit, property, golden and integration tests), and a short
# run of every fuzz target where a nightly toolchain exists (scripts/fuzz-smoke.sh).
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"
cargo fmt --all -- --check
quiet cargo clippy --workspace --all-targets -- -D warnings
log="$(mktemp)"
status=0
cargo test --workspace --quiet >"$log" 2>&1 || status=$?
# Keep the runner's summary lines (and everything on failure); drop the progress dots.
if [ "$status" -ne 0 ]; then
  cat "$log"
else
  grep -E '^test result:' "$log" | grep -v ' 0 passed; 0 failed; 0 ignored; 0 measured' || true
fi
rm -f "$log"
[ "$status" -ne 0 ] && exit "$status"
# A short fuzz run of every target (where nightly exists; skipped with a message otherwise).
bash "$(dirname "$0")/fuzz-smoke.sh"
