#!/usr/bin/env bash
# The distributions and the documentation site, as a user gets them. Every test run (scripts/test-all.sh):
#   1. scripts/build-dist.sh wheel: the x86_64 manylinux2014 abi3 wheel (the same file the Python tests installed)
#      and the sdist, in dist/;
#   2. `twine check` on both;
#   3. `auditwheel show` agrees with the wheel's manylinux_2_17 tag, and no ELF file in it needs a glibc symbol
#      newer than GLIBC_2.17 (fails as soon as one creeps in);
#   4. the wheel installed into a fresh venv with no Rust toolchain on PATH: scripts/dist/smoke_test.py (make, step,
#      check_env, the vector env, built-in policies) under pytest, run outside the repository, with python3;
#   5. the documentation site (docs/site, Sphinx + MyST) built with warnings as errors into docs/site/_build, in
#      .venv-docs with the wheel installed (the CLI page from the workspace's debug `chopperscape`), the rustdoc of
#      the core crates beside it.
# `test-dist.sh release` (scripts/release-check.sh, before a version is tagged) checks everything a release ships:
# the aarch64 and CLI wheels too (steps 1-3 for each), the smoke test with `chopperscape[cli]` and with CPython 3.9
# and 3.13 where installed (the abi3 wheel's oldest and newest claimed), and the sdist built by pip into a fresh
# venv with pip's isolated build (maturin from PyPI; cargo builds into target/dist-sdist/target), then imported.
# Needs python3 with venv, PyPI and rustup (for aarch64). Under CI=true a check that cannot run fails the run; a
# local run says what it skipped and why. Idempotent; quiet on success but for pytest's summary and one
# "N passed" line for the other checks.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"

case "${1:-ci}" in
  ci | --install-only) release=0 ;;
  release) release=1 ;;
  *) say "test-dist.sh: unknown mode '$1' (allowed: ci, release, --install-only)"; exit 2 ;;
esac

if ! command -v python3 >/dev/null 2>&1; then
  skip "the distribution tests (python3 is not installed)"
  exit 0
fi
python3 -m venv --help >/dev/null 2>&1 || apt_install python3-venv \
  || { skip "the distribution tests (python3 -m venv does not work)"; exit 0; }
command -v readelf >/dev/null 2>&1 || apt_install binutils || skip "the glibc check (readelf: binutils could not be installed)"

PIP=(-m pip install --disable-pip-version-check -q)
# The tools: .venv-dist (maturin, ziglang, twine, auditwheel) and .venv-docs (Sphinx, MyST, furo), pinned.
bash scripts/build-dist.sh --install-only || skip "the distribution tests (maturin and ziglang could not be installed)"
DPY=.venv-docs/bin/python
docs=1
[ -x "$DPY" ] || quiet python3 -m venv .venv-docs
if ! "$DPY" -c 'import sphinx, myst_parser, furo' >/dev/null 2>&1 && ! pip_install "$DPY" sphinx myst-parser furo; then
  skip "the documentation site (sphinx, myst-parser and furo could not be installed from PyPI)"
  docs=0
fi
# `test-dist.sh --install-only`: the installs above and nothing else (scripts/test-all.sh runs them early).
[ "${1:-}" = --install-only ] && exit 0
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
checks=0

# 1. Build (a no-op where the Python tests already built this version's wheel). Without PyPI (maturin, ziglang)
# nothing below can run.
if [ "$release" = 1 ]; then set_name=all; else set_name=wheel; fi
if ! build_out=$(bash scripts/build-dist.sh "$set_name" 2>&1); then
  say "$build_out"
  if [ ! -x .venv-dist/bin/maturin ] || ! .venv-dist/bin/python -c 'import ziglang' 2>/dev/null; then
    skip "the distribution tests (maturin and ziglang could not be installed from PyPI)"
    exit 0
  fi
  exit 1
fi
grep '^skipped:' <<<"$build_out" >&2 || true
version=$(project_version)
wheel=$(dist_wheel)
sdist=dist/chopperscape-$version.tar.gz
wheels=("$wheel")
cli_wheel=
if [ "$release" = 1 ]; then
  wheels=(dist/*-"$version"-*.whl)
  cli_wheel=dist/chopperscape_cli-$version-py3-none-manylinux2014_x86_64.manylinux_2_17_x86_64.whl
  [ -f "$cli_wheel" ] || { say "FAILED: scripts/build-dist.sh did not write $cli_wheel"; exit 1; }
fi
for f in "$wheel" "$sdist"; do
  [ -f "$f" ] || { say "FAILED: scripts/build-dist.sh did not write $f; it wrote:"; ls dist >&2; exit 1; }
done

# 2. Metadata, as PyPI would check it.
quiet .venv-dist/bin/twine check --strict "${wheels[@]}" "$sdist"
checks=$((checks + 1))

# 3. The platform tag of every wheel (x86_64; aarch64 too in a release check): auditwheel's verdict, and the newest glibc symbol
# version any ELF file in it needs.
glibc_floor=2.17
for whl in "${wheels[@]}"; do
  arch=$(sed -nE 's/.*manylinux_2_17_([a-z0-9_]+)\.whl$/\1/p' <<<"$whl")
  [ -n "$arch" ] || { say "FAILED: $whl is not tagged manylinux_2_17"; exit 1; }
  report=$(.venv-dist/bin/auditwheel show "$whl" 2>&1) || { say "$report"; exit 1; }
  verdict="consistent with the following platform tag: \"manylinux_2_17_$arch\""
  if ! tr -s ' \n' ' ' <<<"$report" | grep -qF "$verdict"; then
    say "FAILED: auditwheel does not agree with the manylinux_2_17_$arch tag of $whl:"
    say "$report"
    exit 1
  fi
  checks=$((checks + 1))
  rm -rf "$work/unzipped" && mkdir "$work/unzipped"
  .venv-dist/bin/python -m zipfile -e "$whl" "$work/unzipped"
  found=0
  while IFS= read -r -d '' f; do
    head -c 4 "$f" | grep -q 'ELF' || continue
    found=$((found + 1))
    # readelf reads the version needs of an ELF file of any architecture (objdump only the host's).
    newest=$(readelf -W -V "$f" | grep -oE 'GLIBC_[0-9]+(\.[0-9]+)*' | sed 's/GLIBC_//' | sort -uV | tail -1)
    highest=$(printf '%s\n%s\n' "$newest" "$glibc_floor" | sort -V | tail -1)
    if [ -z "$newest" ] || [ "$highest" != "$glibc_floor" ]; then
      say "FAILED: ${f#"$work"/unzipped/} in $whl needs GLIBC_${newest:-?}, newer than its tag's GLIBC_$glibc_floor:"
      readelf -W --dyn-syms "$f" | grep -E "@GLIBC_${newest//./\\.}([^0-9.]|$)" >&2 || true
      exit 1
    fi
  done < <(find "$work/unzipped" -type f -print0)
  [ "$found" -gt 0 ] || { say "FAILED: no ELF file in $whl"; exit 1; }
  checks=$((checks + 1))
done
if [ "$release" = 1 ] && [ "$(uname -m)" != aarch64 ]; then
  say "not run: the aarch64 wheels (this machine is $(uname -m); their tags and glibc are checked above)"
fi

# 4. The wheel in a fresh venv, no cargo or rustc on PATH, run from outside the repository: with python3; in a
# release check as `chopperscape[cli]` (the CLI wheel too) and with the oldest and newest CPython the wheel claims
# (3.9, 3.13) where they are installed (pyenv's too).
find_python() {  # find_python 3.9: a working interpreter of that version, or nothing
  local v=$1 exe
  for exe in "python$v" "$(pyenv root 2>/dev/null)"/versions/"$v".*/bin/python; do
    if "$exe" -c 'import sys, venv; assert sys.version_info[:2] == tuple(map(int, sys.argv[1].split(".")))' "$v" \
      >/dev/null 2>&1; then
      command -v "$exe"
      return 0
    fi
  done
}
cp scripts/dist/smoke_test.py "$work/"
smoke() {  # smoke PYTHON: the smoke test in a fresh venv of that interpreter
  local py=$1 venv log clean_path tool requirement select=()
  venv="$work/wheel-venv-$(basename "$py")"
  quiet "$py" -m venv "$venv"
  # The package's dependencies from PyPI (the pinned versions), then the package as a user names it from dist/
  # alone; in a release check `chopperscape[cli]`: the `cli` extra must resolve to this version's CLI wheel.
  pip_install "$venv/bin/python" gymnasium numpy pytest \
    || skip "the wheel smoke test with $py (gymnasium, numpy, pytest could not be installed from PyPI)"
  requirement="chopperscape==$version"
  if [ "$release" = 1 ]; then
    requirement="chopperscape[cli]==$version"
  else
    # The CLI wheel is a release check's (scripts/release-check.sh).
    select=(--deselect smoke_test.py::test_the_cli_wheel_matches_the_package)
  fi
  quiet "$venv/bin/python" "${PIP[@]}" --no-index --find-links dist "$requirement"
  clean_path="$venv/bin:/usr/local/bin:/usr/bin:/bin"
  for tool in cargo rustc; do
    if PATH=$clean_path command -v "$tool" >/dev/null 2>&1; then
      say "FAILED: $tool is on the restricted PATH ($clean_path); the smoke test needs a PATH without Rust"
      exit 1
    fi
  done
  log="$work/smoke.log"
  if (cd "$work" && env -i HOME="$HOME" PATH="$clean_path" LANG=C.UTF-8 "$venv/bin/python" -m pytest -q \
    -p no:cacheprovider -W error "${select[@]}" smoke_test.py >"$log" 2>&1); then
    grep -E '^[0-9]+ passed' "$log" || tail -1 "$log"
  else
    say "FAILED: the wheel smoke test with $py:"
    cat "$log" >&2
    exit 1
  fi
}
smoke "$(command -v python3)"
if [ "$release" = 1 ]; then
  for v in 3.9 3.13; do
    py=$(find_python "$v")
    if [ -n "$py" ]; then smoke "$py"; else skip "the wheel smoke test with Python $v (not installed)"; fi
  done
fi

# 5. The documentation site, -W: every warning is an error. The CLI page is the workspace's `chopperscape --help`
# (a debug build: the text is the same; the release check installs the CLI wheel instead).
if [ "$docs" = 0 ]; then
  :  # skipped above
elif ! quiet "$DPY" "${PIP[@]}" --force-reinstall --no-deps "$wheel" $cli_wheel \
  || ! pip_install "$DPY" "$wheel"; then
  skip "the documentation site (the wheel's dependencies could not be installed from PyPI)"
else
  cli_exe=$ROOT/.venv-docs/bin/chopperscape
  if [ "$release" = 0 ]; then
    quiet cargo build -q -p chopperscape-cli
    cli_exe=$ROOT/target/debug/chopperscape
  fi
  # rustdoc as strict as sphinx -W: a broken or private intra-doc link fails here.
  RUSTDOCFLAGS="-D warnings" quiet nice -n 10 cargo doc --no-deps -q -p chopperscape-core -p chopperscape-vector \
    -p chopperscape-actionlog
  rm -rf docs/site/_build/html
  CHOPPERSCAPE_CLI=$cli_exe quiet "$DPY" -m sphinx -W --keep-going -q -b html docs/site docs/site/_build/html
  [ -f docs/site/_build/html/rustdoc/chopperscape/index.html ] \
    || { say "FAILED: the rustdoc is not in the site"; exit 1; }
  checks=$((checks + 1))
fi

# 6. A release check only: the sdist, built from its own files only. Its tree is kept at a fixed path and updated
# file by file (files that did not change keep their times), so cargo rebuilds only what changed since the last run.
if [ "$release" = 1 ]; then
  sdist_dir=target/dist-sdist
  mkdir -p "$sdist_dir"
  python3 - "$sdist" "$sdist_dir/src" <<'PY'
import filecmp, os, pathlib, shutil, sys, tarfile, tempfile
archive, dest = sys.argv[1], pathlib.Path(sys.argv[2])
with tempfile.TemporaryDirectory() as tmp:
    with tarfile.open(archive) as tar:
        tar.extractall(tmp, filter="data")
    (top,) = pathlib.Path(tmp).iterdir()
    new = {p.relative_to(top) for p in top.rglob("*") if p.is_file()}
    old = {p.relative_to(dest) for p in dest.rglob("*") if p.is_file()} if dest.exists() else set()
    for rel in old - new:
        (dest / rel).unlink()
    for rel in new:
        src, dst = top / rel, dest / rel
        if not dst.exists() or not filecmp.cmp(src, dst, shallow=False):
            dst.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(src, dst)
            shutil.copymode(src, dst)
PY
  python3 -m venv "$work/sdist-venv"
  command -v cargo >/dev/null 2>&1 || skip "the sdist build (no cargo on PATH; the sdist needs a Rust toolchain)"
  pip_install "$work/sdist-venv/bin/python" gymnasium numpy \
    || skip "the sdist build (gymnasium and numpy could not be installed from PyPI)"
  # As a user's pip does it: an isolated build environment with the sdist's build-system.requires (maturin).
  CARGO_TARGET_DIR="$ROOT/$sdist_dir/target" quiet nice -n 10 "$work/sdist-venv/bin/python" "${PIP[@]}" \
    "$sdist_dir/src"
  (cd "$work" && "$work/sdist-venv/bin/python" -c '
import gymnasium as gym, chopperscape, sys
assert chopperscape.__file__.startswith(sys.prefix), chopperscape.__file__
env = gym.make("ChopperScape-v0", obs_type="features"); env.reset(seed=0); env.step(0)
assert chopperscape.__version__ == sys.argv[1], chopperscape.__version__
' "$version")
  checks=$((checks + 1))
fi

echo "$checks passed, 0 failed (dist: twine, auditwheel and glibc per wheel, docs$([ "$release" = 1 ] && echo ', sdist'))"
