#!/usr/bin/env bash
# Builds the Python distributions into dist/ (gitignored), for x86_64 and aarch64 Linux:
#   chopperscape-VERSION-cp39-abi3-manylinux2014_ARCH.manylinux_2_17_ARCH.whl   the package: one abi3 wheel for
#                                                     every CPython >= 3.9, linked against glibc 2.17 by zig
#   chopperscape-VERSION.tar.gz                       its sdist (builds anywhere with a Rust toolchain)
#   chopperscape_cli-VERSION-py3-none-manylinux2014_ARCH.manylinux_2_17_ARCH.whl   the `chopperscape` command
#                                                     (crates/cli as a maturin `bin` wheel; `chopperscape[cli]`)
# The build tools (maturin, ziglang, both from PyPI at the versions of scripts/constraints.txt) live in .venv-dist
# (with twine and auditwheel, which scripts/test-dist.sh runs). No Docker: `maturin build --zig` links
# with zig's glibc 2.17 stubs, for either architecture from this x86_64 machine. aarch64 needs Rust's standard
# library for aarch64-unknown-linux-gnu, which this script adds with rustup; where it cannot, it says so and builds
# x86_64 only. CHOPPERSCAPE_DIST_ARCHS="x86_64" (or "aarch64") limits the architectures.
# `build-dist.sh wheel` builds what every test run needs, once: the x86_64 package wheel (which the Python tests
# install and scripts/test-dist.sh checks) and the sdist (packed, not built); the aarch64 and CLI wheels are for
# a release (scripts/release-check.sh).
# Idempotent (cargo rebuilds only what changed); quiet on success but for the list of files.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"

case "${1:-all}" in
  all) parts="package cli" ;;
  wheel) parts="package" CHOPPERSCAPE_DIST_ARCHS=x86_64 ;;
  --install-only) parts="" ;;  # the build tools and nothing else (scripts/test-all.sh installs them early)
  *) say "build-dist.sh: unknown set '$1' (allowed: all, wheel, --install-only)"; exit 2 ;;
esac
VENV=.venv-dist
if [ ! -x "$VENV/bin/python" ]; then
  quiet python3 -m venv "$VENV" || { rm -rf "$VENV"; say "build-dist: python3 -m venv does not work"; exit 1; }
fi
"$VENV/bin/python" -c 'import ziglang, twine, auditwheel' >/dev/null 2>&1 && [ -x "$VENV/bin/maturin" ] \
  || pip_install "$VENV/bin/python" maturin ziglang twine auditwheel

[ "${1:-}" = --install-only ] && exit 0

mkdir -p dist
version=$(project_version)
# Only this version's files are kept, so `twine check dist/*` and the install tests see one of each.
find dist -maxdepth 1 -type f \( -name '*.whl' -o -name '*.tar.gz' \) ! -name "*-$version[-.]*" -delete

archs=()
wanted=" ${CHOPPERSCAPE_DIST_ARCHS:-x86_64 aarch64} "
for arch in x86_64 aarch64; do
  target=$arch-unknown-linux-gnu
  if [[ "$wanted" != *" $arch "* ]]; then
    :  # not asked for
  elif ! rustup target list --installed 2>/dev/null | grep -qx "$target" && ! quiet rustup target add "$target"; then
    skip "the $arch wheels (rustup could not add the $target standard library)"
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
  if [[ " $parts " == *" cli "* ]]; then build python/cli "${wheel[@]}"; fi
done
ls dist/*"$version"[-.]*
