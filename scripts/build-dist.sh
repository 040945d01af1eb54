#!/usr/bin/env bash
# Builds the Python distributions into dist/ (gitignored):
#   chopperscape-VERSION-cp39-abi3-manylinux_2_17_x86_64.manylinux2014_x86_64.whl  the package (one abi3 wheel for
#                                                        CPython >= 3.9), linked against glibc 2.17 by zig
#   chopperscape-VERSION.tar.gz                          its sdist (builds with any Rust toolchain)
#   chopperscape_cli-VERSION-py3-none-manylinux_2_17_x86_64.manylinux2014_x86_64.whl  the `chopperscape` command
#                                                        (crates/cli as a maturin `bin` wheel; `chopperscape[cli]`)
# The build tools (maturin, ziglang, both from PyPI) live in .venv-dist. No Docker: `maturin build --zig` links
# with zig's glibc 2.17 stubs. Idempotent (cargo rebuilds only what changed); quiet on success; prints the files.
# aarch64 is not built: rustup cannot fetch the aarch64-unknown-linux-gnu standard library here (only the package
# registries are reachable), see python/README.md, "Wheels".
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

export PATH="$ROOT/$VENV/bin:$PATH"
# build DIR ARGS...: maturin run in DIR (where its pyproject.toml is), writing into dist/.
build() { local dir=$1; shift; (cd "$dir" && quiet nice -n 10 maturin "$@" --out "$ROOT/dist"); }
wheel=(build --release --zig --compatibility manylinux2014 --target x86_64-unknown-linux-gnu)
build python "${wheel[@]}"
build python sdist
build python/cli "${wheel[@]}"
ls dist/*"$version"*
