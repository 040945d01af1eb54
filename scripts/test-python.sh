#!/usr/bin/env bash
# The Python package's tests: a virtual environment at .venv with the package (the x86_64 abi3 wheel that
# scripts/build-dist.sh builds once, in release mode; scripts/test-dist.sh checks that same file), gymnasium, numpy,
# pytest, pygame (for render_mode="human"), the learning tool chain and the quality gate, every version pinned by
# scripts/constraints.txt; then the gate and pytest. Idempotent: the wheel is reinstalled only when it changed.
# Quiet on success but for pytest's summaries. Under CI=true a package that cannot be installed, or a test that
# pytest skips, fails the run (python/tests/conftest.py); a local run says what it skipped.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"

command -v python3 >/dev/null 2>&1 || { skip "the Python tests (python3 is not installed)"; exit 0; }
if [ ! -x .venv/bin/python ]; then
  if ! python3 -m venv .venv >/dev/null 2>&1; then
    rm -rf .venv
    apt_install python3-venv || { skip "the Python tests (python3 -m venv does not work)"; exit 0; }
    quiet python3 -m venv .venv
  fi
fi
PY=.venv/bin/python
# Everything the tests import, in one resolution, at the pinned versions: gymnasium, numpy, pytest; pygame; the
# learning tool chain (torch from PyPI, about 5 GB with its CUDA libraries, of which the CPU build is all the recipe
# uses; Stable-Baselines3, matplotlib); onnx and onnxruntime (the export and its logits check); Minari with HDF5 and
# pillow (the dataset tests); the quality gate's ruff, mypy and import-linter. The stamp is the constraints file's
# hash: a new pin reinstalls.
deps_stamp=.venv/.chopperscape-deps
deps_hash=$(sha256sum "$CONSTRAINTS" | cut -d' ' -f1)
if [ "$(cat "$deps_stamp" 2>/dev/null)" != "$deps_hash" ]; then
  if pip_install "$PY" gymnasium numpy pytest pygame torch stable-baselines3 matplotlib onnx onnxruntime \
    "minari[hdf5]" pillow ruff mypy import-linter; then
    echo "$deps_hash" >"$deps_stamp"
  else
    skip "the Python test dependencies of scripts/constraints.txt could not all be installed; tests that need them skip"
  fi
fi

# Ray RLlib (python/tests/test_rllib.py, docs/rllib.md). Ray pins gymnasium==1.2.2, so RLlib gets its own
# environment, .venv-rllib, with ray[rllib] from PyPI (scripts/constraints.txt without its gymnasium line: Ray's
# own pin decides); torch is not installed a second time: a .pth file puts .venv's site-packages at the end of its
# path, so torch comes from .venv while Ray's own pins (gymnasium 1.2.2, numpy, ...) come first. This package is
# linked in from .venv. A fresh install: 54 s and 0.8 GB (it was 195 s and 6.1 GB with its own torch).
# CHOPPERSCAPE_RLLIB=0 skips it (a local run only: under CI=true that fails).
RPY=.venv-rllib/bin/python
rstamp=.venv-rllib/.chopperscape-rllib
rllib=${CHOPPERSCAPE_RLLIB:-1}
[ "$rllib" = 0 ] && skip "the RLlib tests (CHOPPERSCAPE_RLLIB=0)"
if [ "$rllib" = 1 ] && { [ "$(cat "$rstamp" 2>/dev/null)" != "$deps_hash shared-torch" ] || [ ! -x "$RPY" ]; }; then
  [ -x "$RPY" ] || quiet python3 -m venv .venv-rllib
  ray_constraints=$(mktemp)
  grep -v '^gymnasium==' "$CONSTRAINTS" >"$ray_constraints"
  if ! CONSTRAINTS=$ray_constraints pip_install "$RPY" "ray[rllib]" pytest; then
    rm -f "$ray_constraints"
    skip "the RLlib tests (could not install ray[rllib] from PyPI)"
    rllib=0
  else
    echo "$deps_hash shared-torch" >"$rstamp"
  fi
  rm -f "$ray_constraints"
fi
# `test-python.sh --install-only`: the installs above and nothing else (scripts/test-all.sh runs them early, in the
# background, while the Rust part builds).
[ "${1:-}" = --install-only ] && exit 0

# The package: this version's x86_64 abi3 wheel, built (or found up to date) by scripts/build-dist.sh.
bash scripts/build-dist.sh wheel >/dev/null
wheel=$(dist_wheel)
stamp=.venv/.chopperscape-build
hash=$(sha256sum "$wheel" | cut -d' ' -f1)
if [ "$(cat "$stamp" 2>/dev/null)" != "$hash" ] || ! "$PY" -c "import chopperscape._core" >/dev/null 2>&1; then
  quiet "$PY" -m pip install --disable-pip-version-check -q --no-deps --force-reinstall "$wheel"
  echo "$hash" >"$stamp"
fi

# run_pytest PYTHON PATH...: pytest quietly, from the repository root (so that python/chopperscape, sources without
# the extension, is not importable); prints its summary line, or everything and exits with its status on failure.
run_pytest() {
  local py=$1 log rc
  shift
  log=$(mktemp)
  if SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy "$py" -m pytest -q -p no:cacheprovider -c python/pyproject.toml \
    -rs "$@" >"$log" 2>&1; then
    grep -E '^SKIPPED' "$log" | sed 's/^SKIPPED/skipped: pytest/' >&2 || true
    grep -E '^[0-9]+ passed' "$log" || tail -1 "$log"
    rm -f "$log"
  else
    rc=$?
    cat "$log" >&2
    rm -f "$log"
    exit "$rc"
  fi
}
# The quality gate, as strict as fmt and clippy are for the Rust side: ruff's lint and format check over every
# Python file of the repository (ruff.toml), mypy over the package (python/pyproject.toml), stubtest of the
# compiled module against _core.pyi (python/stubtest-allowlist.txt says what it may report, and why), and the
# docstring examples run as doctests. The tools are pinned (scripts/constraints.txt): a release's new rules are
# adopted on purpose.
quiet .venv/bin/ruff check --no-cache .
quiet .venv/bin/ruff format --check --no-cache .
(cd python && quiet ../.venv/bin/mypy --no-incremental)
# The package's layers (python/pyproject.toml, [tool.importlinter]; ARCHITECTURE.md states them), from the sources.
(cd python && quiet ../.venv/bin/lint-imports --no-cache)
(cd "$(mktemp -d)" && quiet "$ROOT/$PY" -m mypy.stubtest chopperscape._core --allowlist "$ROOT/python/stubtest-allowlist.txt")
pkg=$("$PY" -c 'import chopperscape, os; print(os.path.dirname(os.path.abspath(chopperscape.__file__)))')
# Doctests of the installed package; the RLlib module's run under .venv-rllib below.
run_pytest "$PY" --doctest-modules "$pkg" --ignore="$pkg/integrations/rllib"
run_pytest "$PY" python/tests --ignore=python/tests/test_rllib.py --ignore=python/tests/test_rllib_meanstd.py

[ "$rllib" = 1 ] || exit 0
rsite=$("$RPY" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
"$PY" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])' >"$rsite/zz-chopperscape-venv.pth"
"$RPY" -c 'import torch' >/dev/null 2>&1 \
  || { skip "the RLlib tests (torch is not importable from .venv, which they share)"; exit 0; }
if [ -e "$rsite/chopperscape" ] && [ ! -L "$rsite/chopperscape" ]; then  # a copy installed there by hand
  quiet "$RPY" -m pip uninstall --disable-pip-version-check -y -q chopperscape || true
  rm -rf "$rsite/chopperscape"
fi
ln -sfn "$pkg" "$rsite/chopperscape"
run_pytest "$RPY" python/tests/test_rllib.py python/tests/test_rllib_meanstd.py --doctest-modules "$pkg/integrations/rllib"
