# Shared helpers for the project's scripts. Source it: `. "$(dirname "$0")/lib.sh"`.
# Everything here is idempotent and quiet on success.

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export ROOT

say() { printf '%s\n' "$*" >&2; }

# skip WHAT: a part of the tests that cannot run on this machine. A local run says so ("skipped: WHAT"; the test
# command repeats every such line at its end); under CI=true nothing may be skipped, so it fails the run instead.
# It exits the calling script in CI: call it in the script's own shell, not in $(...).
skip() {
  if [ "${CI:-}" = true ]; then
    say "FAILED: $* (CI=true: nothing may be skipped)"
    exit 1
  fi
  say "skipped: $*"
}

# The pinned versions of every Python package the tests, the builds and the docs install (see its header).
CONSTRAINTS="$ROOT/scripts/constraints.txt"
export CONSTRAINTS
# pip_install PYTHON ARGS...: `pip install` into PYTHON's environment, quietly, within the pinned versions.
pip_install() {
  local py=$1
  shift
  PIP_CONSTRAINT="$CONSTRAINTS" quiet "$py" -m pip install --disable-pip-version-check -q "$@"
}

# Runs a command quietly; on failure prints its output and returns its status.
quiet() {
  local log
  log="$(mktemp)"
  if "$@" >"$log" 2>&1; then
    rm -f "$log"
  else
    local rc=$?
    cat "$log" >&2
    rm -f "$log"
    return "$rc"
  fi
}

# apt_install PKG... — installs missing Debian packages when we may (root), else says what it could not install.
# Returns 1 when something is still missing, so callers can skip the tests that need it (with `skip`).
apt_install() {
  local missing=()
  for p in "$@"; do
    dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    if [ ! -f /tmp/.chopperscape-apt-updated ]; then
      quiet apt-get update && touch /tmp/.chopperscape-apt-updated
    fi
    DEBIAN_FRONTEND=noninteractive quiet apt-get install -y --no-install-recommends "${missing[@]}" && return 0
  fi
  say "could not install ${missing[*]} (needs root and apt-get)"
  return 1
}

# The version of every crate and of the Python package (`[workspace.package] version`).
project_version() { sed -n 's/^version = "\(.*\)"/\1/p' "$ROOT/Cargo.toml" | head -1; }

# dist_wheel [ARCH]: the path of this version's abi3 wheel of the package in dist/ (x86_64 unless named).
dist_wheel() {
  local arch=${1:-x86_64}
  echo "$ROOT/dist/chopperscape-$(project_version)-cp39-abi3-manylinux2014_$arch.manylinux_2_17_$arch.whl"
}
