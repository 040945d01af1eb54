#!/usr/bin/env bash
# The Python package's tests: a virtual environment at .venv with the package (built by maturin in release
# mode from crates/python), gymnasium, numpy, pytest and pygame (for render_mode="human"), then pytest.
# Idempotent: the extension is rebuilt only when its sources changed. Quiet on success but for pytest's summary.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"

if ! command -v python3 >/dev/null 2>&1; then
  say "skipped: the Python tests (python3 is not installed)"
  exit 0
fi
if [ ! -x .venv/bin/python ]; then
  if ! python3 -m venv .venv >/dev/null 2>&1; then
    rm -rf .venv
    apt_install python3-venv || { say "skipped: the Python tests (python3 -m venv does not work)"; exit 0; }
    quiet python3 -m venv .venv
  fi
fi
PY=.venv/bin/python
quiet "$PY" -m pip install --disable-pip-version-check -q "maturin>=1.9.4,<2" "gymnasium>=1.1" numpy "pytest>=7"
"$PY" -c "import pygame" >/dev/null 2>&1 || quiet "$PY" -m pip install --disable-pip-version-check -q pygame \
  || say "skipped: pygame (render_mode=\"human\" is tested as unavailable instead)"
# The learning tool chain (the PPO recipe, the SB3 adapter, the plot): torch from PyPI (about 5 GB with its CUDA
# libraries, ~2 minutes on a fresh machine; the CPU is all the recipe uses), Stable-Baselines3, matplotlib.
"$PY" -c "import torch, stable_baselines3, matplotlib" >/dev/null 2>&1 \
  || quiet "$PY" -m pip install --disable-pip-version-check -q torch "stable-baselines3>=2.4" matplotlib \
  || say "skipped: torch / stable-baselines3 / matplotlib could not be installed; the learning tests are skipped"
# The ONNX export (python -m chopperscape.learn.export): onnx writes its metadata, onnxruntime checks its logits.
"$PY" -c "import onnx, onnxruntime" >/dev/null 2>&1 \
  || quiet "$PY" -m pip install --disable-pip-version-check -q onnx onnxruntime \
  || say "skipped: onnx / onnxruntime could not be installed; the export tests are skipped"
"$PY" -c "import minari, h5py, PIL" >/dev/null 2>&1 \
  || quiet "$PY" -m pip install --disable-pip-version-check -q "minari[hdf5]" pillow \
  || say "skipped: minari (the Minari dataset tests are skipped)"

# Rebuild the extension only when something it is built from changed.
stamp=.venv/.chopperscape-build
sources=$(find Cargo.toml Cargo.lock python/pyproject.toml python/chopperscape crates/core crates/vector crates/actionlog \
  crates/python \
  -type f -not -path '*/__pycache__/*' | LC_ALL=C sort)
hash=$(printf '%s\n' "$sources" | xargs cat | sha256sum | cut -d' ' -f1)
if [ "$(cat "$stamp" 2>/dev/null)" != "$hash" ] || ! "$PY" -c "import chopperscape._core" >/dev/null 2>&1; then
  PATH="$ROOT/.venv/bin:$PATH" quiet "$PY" -m pip install --disable-pip-version-check -q --no-build-isolation \
    --no-deps --force-reinstall ./python
  echo "$hash" >"$stamp"
fi

# run_pytest PYTHON PATH...: pytest quietly, from the repository root (so that python/chopperscape, sources without
# the extension, is not importable); prints its summary line, or everything and exits with its status on failure.
run_pytest() {
  local py=$1 log rc
  shift
  log=$(mktemp)
  if SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy "$py" -m pytest -q -p no:cacheprovider -c python/pyproject.toml \
    "$@" >"$log" 2>&1; then
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
# docstring examples run as doctests. The tools are pinned: a release's new rules are adopted on purpose.
GATE_SPEC="ruff==0.17.6 mypy==2.4.1"
if [ "$(cat .venv/.chopperscape-gate 2>/dev/null)" != "$GATE_SPEC" ]; then
  # shellcheck disable=SC2086
  quiet "$PY" -m pip install --disable-pip-version-check -q $GATE_SPEC
  echo "$GATE_SPEC" >.venv/.chopperscape-gate
fi
quiet .venv/bin/ruff check --no-cache .
quiet .venv/bin/ruff format --check --no-cache .
(cd python && quiet ../.venv/bin/mypy --no-incremental)
(cd "$(mktemp -d)" && quiet "$ROOT/$PY" -m mypy.stubtest chopperscape._core --allowlist "$ROOT/python/stubtest-allowlist.txt")
pkg=$("$PY" -c 'import chopperscape, os; print(os.path.dirname(os.path.abspath(chopperscape.__file__)))')
# Doctests of the installed package; the 0.1 shims (they warn by design) and the RLlib module (run under
# .venv-rllib below) are left out.
shims=()
for f in "$pkg"/*.py; do grep -q '^__chopperscape_shim__ = True' "$f" && shims+=("--ignore=$f"); done
run_pytest "$PY" --doctest-modules "$pkg" "${shims[@]}" --ignore="$pkg/integrations/rllib.py"

run_pytest "$PY" python/tests

# Ray RLlib (python/tests/test_rllib.py, docs/rllib.md). Ray pins gymnasium==1.2.2, so RLlib gets its own
# environment, .venv-rllib, with ray[rllib] from PyPI; torch is not installed a second time: a .pth file puts
# .venv's site-packages at the end of its path, so torch comes from .venv while Ray's own pins (gymnasium 1.2.2,
# numpy, ...) come first. This package is linked in from .venv (built above). A fresh install: 54 s and 0.8 GB
# (it was 195 s and 6.1 GB with its own torch). CHOPPERSCAPE_RLLIB=0 skips it; where it cannot be installed, the
# RLlib tests are skipped.
RAY_SPEC="ray[rllib]==2.60.0"
RPY=.venv-rllib/bin/python
rstamp=.venv-rllib/.chopperscape-rllib
if [ "${CHOPPERSCAPE_RLLIB:-1}" = 0 ]; then
  say "skipped: the RLlib tests (CHOPPERSCAPE_RLLIB=0)"
  exit 0
fi
if [ "$(cat "$rstamp" 2>/dev/null)" != "$RAY_SPEC shared-torch" ] || [ ! -x .venv-rllib/bin/ray ]; then
  [ -x "$RPY" ] || quiet python3 -m venv .venv-rllib
  if ! quiet "$RPY" -m pip install --disable-pip-version-check -q "$RAY_SPEC" "pytest>=7"; then
    say "skipped: the RLlib tests (could not install $RAY_SPEC from PyPI)"
    exit 0
  fi
  echo "$RAY_SPEC shared-torch" >"$rstamp"
fi
rsite=$("$RPY" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
"$PY" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])' >"$rsite/zz-chopperscape-venv.pth"
if ! "$RPY" -c 'import torch' >/dev/null 2>&1; then
  say "skipped: the RLlib tests (torch is not importable from .venv, which they share)"
  exit 0
fi
if [ -e "$rsite/chopperscape" ] && [ ! -L "$rsite/chopperscape" ]; then  # a copy installed there by hand
  quiet "$RPY" -m pip uninstall --disable-pip-version-check -y -q chopperscape || true
  rm -rf "$rsite/chopperscape"
fi
ln -sfn "$pkg" "$rsite/chopperscape"
run_pytest "$RPY" python/tests/test_rllib.py --doctest-modules "$pkg/integrations/rllib.py"
