#!/usr/bin/env bash
# The check to run before a version is tagged (its result goes in CHANGELOG.md under that version): everything the
# test command checks on every commit (scripts/test-all.sh), then what only a release ships, which CI leaves out to
# stay within its time (docs/testing.md): the aarch64 wheels and the `chopperscape` command's wheels (x86_64 and
# aarch64, through zig), twine, auditwheel and glibc for each, the smoke test as `chopperscape[cli]` and with
# CPython 3.9 and 3.13 where installed, and the sdist built by pip in a fresh venv. About 30 minutes more on a
# 2-core machine. Skips are reported, not hidden; under CI=true they fail.
set -euo pipefail
. "$(dirname "$0")/lib.sh"
cd "$ROOT"
start=$SECONDS
bash scripts/test-all.sh
part_start=$SECONDS
bash scripts/test-dist.sh release
printf 'time: %-6s %4d s\n' release $((SECONDS - part_start))
printf 'time: %-6s %4d s (%d min)\n' total $((SECONDS - start)) $(((SECONDS - start + 59) / 60))
echo "release check of $(project_version): passed"
