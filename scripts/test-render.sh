#!/usr/bin/env bash
# The renderer's tests (issue 3): golden frames, incremental == full redraw, observation types, image export,
# the sprite-size unit test; then the core built without the `export` feature for wasm32, as the web crate uses it.
# Regenerate the golden frames with: UPDATE_GOLDEN=1 cargo test -p chopperscape-core --test render_golden
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"

log="$(mktemp)"
trap 'rm -f "$log"' EXIT
status=0
cargo test -p chopperscape-core --test render_golden --test render_incremental --test render_observations \
  --test render_export >"$log" 2>&1 || status=$?
cargo test -p chopperscape-core --lib render:: >>"$log" 2>&1 || status=$?
if [ "$status" -ne 0 ]; then
  cat "$log" >&2
  exit "$status"
fi
grep -E '^test result:' "$log" | grep -v ' 0 passed' || true

if rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown || quiet rustup target add wasm32-unknown-unknown; then
  quiet cargo build -p chopperscape-core --no-default-features --target wasm32-unknown-unknown
else
  say "skipped: the wasm32 build of the core without 'export' (could not add the wasm32-unknown-unknown target)"
fi
