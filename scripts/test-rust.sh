#!/usr/bin/env bash
# The Rust tests of every crate: unit, property, golden and integration tests.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"
cargo test --workspace --quiet 2>&1 | grep -vE '^(running 0 tests|test result: ok. 0 passed.*|)$' || true
test "${PIPESTATUS[0]}" -eq 0
