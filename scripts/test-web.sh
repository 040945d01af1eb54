#!/usr/bin/env bash
# The browser tests: builds the page (wasm + HTML) into web/dist, then drives it in Debian's headless Chromium
# with playwright-core under node's test runner. The wrapper's Rust tests run with the workspace (test-rust.sh).
# Installs Chromium, Node and the npm packages when it may; otherwise says what it skipped.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"

if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  apt_install nodejs npm || { say "skipped: browser tests (Node.js and npm are missing)"; exit 0; }
fi
if [ "$(node -p 'process.versions.node.split(".")[0]')" -lt 20 ]; then
  say "skipped: browser tests (playwright-core needs Node.js 20 or newer; this is $(node --version))"
  exit 0
fi
apt_install chromium || { say "skipped: browser tests (Chromium is missing)"; exit 0; }

bash scripts/build-web.sh
(cd web/tests && quiet npm ci --no-audit --no-fund --loglevel=error)

log="$(mktemp)"
trap 'rm -f "$log"' EXIT
if (cd web/tests && node --test --test-reporter=spec page.test.mjs cli.test.mjs) >"$log" 2>&1; then
  # Quiet on success: keep node's summary lines (tests, pass, fail, ...).
  grep -E '^ℹ (tests|pass|fail|skipped|duration_ms)' "$log" | sed 's/^/web: /'
else
  cat "$log" >&2
  exit 1
fi
