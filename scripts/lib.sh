# Shared helpers for the project's scripts. Source it: `. "$(dirname "$0")/lib.sh"`.
# Everything here is idempotent and quiet on success.

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export ROOT

say() { printf '%s\n' "$*" >&2; }

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

# apt_install PKG... — installs missing Debian packages when we may (root), else says what was skipped.
# Returns 1 when something is still missing, so callers can skip the tests that need it.
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
  say "skipped: could not install ${missing[*]} (needs root and apt-get); the tests that need them are skipped"
  return 1
}
