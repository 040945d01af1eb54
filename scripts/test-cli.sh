#!/usr/bin/env bash
# Tests of the `chopperscape` command line that need more than `cargo test`: `play` for real in a window
# under Xvfb, driven by xdotool. (The integration tests of every command run with `cargo test --workspace`;
# `cli_test_deps` installs what they need too: ffmpeg for the .mp4 test.)
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"

# Debian packages the command-line tests need: ffmpeg (.mp4 recording, ffprobe), and for `play` under a virtual
# display: Xvfb (xvfb-run), xdotool and the X11 libraries minifb loads at run time.
cli_test_deps() {
  apt_install ffmpeg || skip "the .mp4 checks against ffmpeg (ffmpeg could not be installed)"
  apt_install xvfb xauth xdotool libx11-6 libxcursor1 libxrandr2 libxi6 libxkbcommon0
}

# `play --seed 3` in a virtual display: hold Up for a second, then Esc. The saved actions must hold Up (3)
# actions, the chopper must end higher than it started, and `replay` must reproduce the episode.
play_under_xvfb() {
  local tmp bin out log pid wid
  tmp="$(mktemp -d)"
  trap 'rm -rf "$tmp"' RETURN
  quiet cargo build -p chopperscape-cli
  bin="$ROOT/target/debug/chopperscape"
  out="$tmp/play.out"
  log="$tmp/actions.json"
  xvfb-run -a -s "-screen 0 1024x768x24" bash -c '
    set -euo pipefail
    "$1" play --seed 3 --save-actions "$2" >"$3" 2>"$3.err" &
    pid=$!
    wid="$(timeout 30 xdotool search --sync --name "^ChopperScape$" | head -n1)"
    xdotool windowfocus --sync "$wid" 2>/dev/null || xdotool windowfocus "$wid"
    sleep 0.5
    xdotool keydown Up
    sleep 1
    xdotool keyup Up
    sleep 0.3
    xdotool keydown Escape
    sleep 0.3
    xdotool keyup Escape
    wait "$pid"
  ' _ "$bin" "$log" "$out" || { cat "$out.err" >&2; say "FAILED: play under Xvfb did not run to the end"; return 1; }
  python3 - "$out" "$log" <<'PY'
import json, sys
result = json.loads(open(sys.argv[1]).read().strip().splitlines()[-1])
log = json.load(open(sys.argv[2]))
ups = log["actions"].count("3")
assert ups >= 5, f"expected the held Up key to give Up (3) actions, got {ups}: {log['actions']}"
assert result["chopper"][1] < result["start"][1], f"the chopper did not move up: {result}"
assert log["steps"] == result["steps"] and log["return"] == result["return"], (log, result)
PY
  local replayed
  replayed="$("$bin" replay "$log" --json)"
  python3 - "$out" "$replayed" <<'PY'
import json, sys
played = json.loads(open(sys.argv[1]).read().strip().splitlines()[-1])
replayed = json.loads(sys.argv[2])
assert played == replayed, f"replay differs: played {played}, replayed {replayed}"
PY
  echo "play under Xvfb: ok (held Up moved the chopper; the saved actions replay to the same result)"
}

if [ "${1:-}" = --install-only ]; then  # the installs and nothing else (scripts/test-all.sh runs them early)
  cli_test_deps || true
  exit 0
fi
if cli_test_deps; then
  play_under_xvfb
else
  skip "the window test of \`chopperscape play\` (Xvfb, xdotool or the X11 libraries could not be installed)"
fi
