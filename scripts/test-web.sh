#!/usr/bin/env bash
# The browser tests: builds the page (wasm + HTML) into web/dist, then drives it in Debian's headless Chromium
# with playwright-core under node's test runner. The wrapper's Rust tests run with the workspace (test-rust.sh).
# Installs Chromium, Node and the npm packages when it may; otherwise a local run says what it skipped (under
# CI=true that fails the run).
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"

if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  apt_install nodejs npm || { skip "browser tests (Node.js and npm are missing)"; exit 0; }
fi
if [ "$(node -p 'process.versions.node.split(".")[0]')" -lt 20 ]; then
  skip "browser tests (playwright-core needs Node.js 20 or newer; this is $(node --version))"
  exit 0
fi
apt_install chromium || { skip "browser tests (Chromium is missing)"; exit 0; }

bash scripts/build-web.sh --install-only
npm_stamp=web/tests/node_modules/.chopperscape-npm
npm_hash=$(sha256sum web/tests/package-lock.json | cut -d' ' -f1)
if [ "$(cat "$npm_stamp" 2>/dev/null)" != "$npm_hash" ]; then
  (cd web/tests && quiet npm ci --no-audit --no-fund --loglevel=error)
  echo "$npm_hash" >"$npm_stamp"
fi
# `test-web.sh --install-only`: the installs above and nothing else (scripts/test-all.sh runs them early).
[ "${1:-}" = --install-only ] && exit 0

bash scripts/build-web.sh

log="$(mktemp)"
trap 'rm -f "$log"' EXIT
if (cd web/tests && node --test --test-reporter=spec page.test.mjs cli.test.mjs train.test.mjs) >"$log" 2>&1; then
  # Quiet on success: keep node's summary lines (tests, pass, fail, ...).
  grep -E '^ℹ (tests|pass|fail|skipped|duration_ms)' "$log" | sed 's/^/web: /'
else
  cat "$log" >&2
  exit 1
fi
