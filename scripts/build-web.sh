#!/usr/bin/env bash
# Builds the browser page into web/dist/: the core compiled to wasm32 through wasm-bindgen (pkg/), plus the
# page's HTML, JavaScript and CSS. Installs the wasm target and wasm-bindgen-cli 0.2.130 (the version the
# crate pins) when missing. Downloads nothing at build time beyond those; no wasm-pack.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"

WASM_BINDGEN_VERSION=0.2.130
quiet rustup target add wasm32-unknown-unknown
if [ "$(wasm-bindgen --version 2>/dev/null || true)" != "wasm-bindgen $WASM_BINDGEN_VERSION" ]; then
  say "installing wasm-bindgen-cli $WASM_BINDGEN_VERSION (once; a few minutes)"
  # A build tool, not something shipped: its output is the same at any optimisation, so it is built at opt-level 1
  # with parallel codegen and no LTO, which compiles in about half the time of cargo install's release profile.
  CARGO_PROFILE_RELEASE_OPT_LEVEL=1 CARGO_PROFILE_RELEASE_CODEGEN_UNITS=16 CARGO_PROFILE_RELEASE_LTO=false \
    quiet cargo install wasm-bindgen-cli --version "$WASM_BINDGEN_VERSION"
fi

# `build-web.sh --install-only`: the tools above and nothing else (scripts/test-all.sh installs them early).
[ "${1:-}" = --install-only ] && exit 0

# Optimised for size, without debug info: tract (the trained agent's inference) makes most of the module, and this
# takes it from 15.7 MB to 12.0 MB (2.7 MB gzipped); the page needs 30 steps a second of a far faster core. The
# learner's arithmetic (candle's tensors, gemm's kernels, the learner itself) is optimised for speed instead: it is
# what the "Train" control spends its time in.
fast=()
for crate in chopperscape-learn candle-core gemm gemm-common gemm-f32; do
  fast+=(--config "profile.release.package.$crate.opt-level=3")
done
CARGO_PROFILE_RELEASE_OPT_LEVEL=s CARGO_PROFILE_RELEASE_DEBUG=0 \
  quiet cargo build -p chopperscape-web --release --target wasm32-unknown-unknown "${fast[@]}"
target_dir="$(cargo metadata --format-version 1 --no-deps | sed -n 's/.*"target_directory":"\([^"]*\)".*/\1/p')"

# Build beside dist, then swap, so a failed build never leaves a half-written page.
out="web/dist.tmp"
rm -rf "$out"
mkdir -p "$out"
quiet wasm-bindgen --target web --no-typescript --out-dir "$out/pkg" \
  "$target_dir/wasm32-unknown-unknown/release/chopperscape_web.wasm"
cp web/index.html web/main.js web/train.js web/train-worker.js web/style.css "$out/"
# The trained agents the page offers ("Watch: trained agent", the "Agent" menu): the exports of
# models/ppo-features.pt and models/ppo-pixels.pt (frames alone).
mkdir -p "$out/models"
cp models/ppo-features.onnx models/ppo-pixels.onnx "$out/models/"
rm -rf web/dist
mv "$out" web/dist
