#!/usr/bin/env bash
# A short run of every fuzz target in fuzz/ (FUZZ_SECONDS each, default 10), where a nightly toolchain exists:
# the targets are built as `cargo fuzz` builds them (libFuzzer, sanitizer coverage, `--cfg fuzzing`), without
# needing cargo-fuzz itself. Without nightly it says so and skips. For a long run: FUZZ_SECONDS=300.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT/fuzz"

if ! cargo +nightly --version >/dev/null 2>&1; then
  skip "the fuzz smoke run (no nightly toolchain: rustup toolchain install nightly)"
  exit 0
fi
host=$(rustc +nightly -vV | sed -n 's/^host: //p')
export RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing -Cdebug-assertions -Coverflow-checks"
quiet cargo +nightly build --release --bins --target "$host"
seconds=${FUZZ_SECONDS:-10}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for bin in $(sed -n 's/^name = "\(.*\)"$/\1/p' Cargo.toml | grep -v '^chopperscape-fuzz$'); do
  mkdir -p "$work/$bin"
  # Committed seeds (fuzz/seeds/TARGET/), read as a second corpus; new inputs go to the scratch folder only.
  seeds=()
  if [ -d "$ROOT/fuzz/seeds/$bin" ]; then seeds=("$ROOT/fuzz/seeds/$bin"); fi
  if ! (cd "$work" && "$ROOT/fuzz/target/$host/release/$bin" "$work/$bin" "${seeds[@]}" -max_total_time="$seconds" \
    -max_len=4096 >"$work/$bin.log" 2>&1); then
    cat "$work/$bin.log" >&2
    say "fuzz target $bin failed: the crashing input is above (rerun it with FUZZ_SECONDS=$seconds)"
    exit 1
  fi
  say "fuzz $bin: $(grep -Eo 'Done [0-9]+ runs in [0-9]+ second' "$work/$bin.log" | tail -1)s, no failure"
done
