#!/usr/bin/env bash
# Builds the Python distributions into dist/ (gitignored), for x86_64 and aarch64 Linux:
#   chopperscape-VERSION-cp39-abi3-manylinux2014_ARCH.manylinux_2_17_ARCH.whl   the package: one abi3 wheel for
#                                                     every CPython >= 3.9, linked against glibc 2.17 by zig
#   chopperscape-VERSION.tar.gz                       its sdist (builds anywhere with a Rust toolchain)
#   chopperscape_cli-VERSION-py3-none-manylinux2014_ARCH.manylinux_2_17_ARCH.whl   the `chopperscape` command
#                                                     (crates/cli as a maturin `bin` wheel; `chopperscape[cli]`)
# The build tools (maturin, ziglang, both from PyPI) live in .venv-dist. No Docker: `maturin build --zig` links
# with zig's glibc 2.17 stubs, for either architecture from this x86_64 machine. aarch64 needs Rust's standard
# library for aarch64-unknown-linux-gnu, which this script adds with rustup; where it cannot, it says so and builds
# x86_64 only. CHOPPERSCAPE_DIST_ARCHS="x86_64" (or "aarch64") limits the architectures.
# Idempotent (cargo rebuilds only what changed); quiet on success but for the list of files.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"

MATURIN_SPEC="maturin>=1.9.4,<2"
ZIG_SPEC="ziglang>=0.13,<0.18"
VENV=.venv-dist
if [ ! -x "$VENV/bin/python" ]; then
  quiet python3 -m venv "$VENV" || { rm -rf "$VENV"; say "build-dist: python3 -m venv does not work"; exit 1; }
fi
"$VENV/bin/python" -c 'import ziglang' >/dev/null 2>&1 && [ -x "$VENV/bin/maturin" ] \
  || quiet "$VENV/bin/python" -m pip install --disable-pip-version-check -q "$MATURIN_SPEC" "$ZIG_SPEC"

mkdir -p dist
version=$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -1)
# Only this version's files are kept, so `twine check dist/*` and the install tests see one of each.
find dist -maxdepth 1 -type f \( -name '*.whl' -o -name '*.tar.gz' \) ! -name "*-$version[-.]*" -delete

archs=()
wanted=" ${CHOPPERSCAPE_DIST_ARCHS:-x86_64 aarch64} "
for arch in x86_64 aarch64; do
  target=$arch-unknown-linux-gnu
  if [[ "$wanted" != *" $arch "* ]]; then
    :  # not asked for
  elif ! rustup target list --installed 2>/dev/null | grep -qx "$target" && ! quiet rustup target add "$target"; then
    say "skipped: the $arch wheels (rustup could not add the $target standard library)"
  else
    archs+=("$arch")
    continue
  fi
  rm -f dist/*"_$arch.whl"  # no wheel of an earlier build is left to pass for this one
done

export PATH="$ROOT/$VENV/bin:$PATH"
# build DIR ARGS...: maturin run in DIR (where its pyproject.toml is), writing into dist/.
build() { local dir=$1; shift; (cd "$dir" && quiet nice -n 10 maturin "$@" --out "$ROOT/dist"); }
build python sdist
for arch in "${archs[@]}"; do
  wheel=(build --release --zig --compatibility manylinux2014 --target "$arch-unknown-linux-gnu")
  build python "${wheel[@]}"
  build python/cli "${wheel[@]}"
done
ls dist/*"$version"[-.]*
