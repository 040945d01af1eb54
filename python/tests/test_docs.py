"""The docs match the code, checked: every repository path that a Markdown file names exists, and SPEC's table of
options is the core's (`_core.OPTIONS`) cell by cell."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from chopperscape import _core

ROOT = Path(__file__).resolve().parents[2]
#: Files that name what no longer exists on purpose: the changelog's history.
HISTORY = {"CHANGELOG.md"}
#: A path that names a source file must name one that exists, even without its folder (`obs_pipeline.rs`).
SOURCE = re.compile(r"\.(rs|py|pyi|sh|mjs|toml)$")
#: A path in backticks or a Markdown link target.
NAMED = re.compile(r"`([^`\s]+)`|\]\(([^)\s#]+)")


def git(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True, text=True, check=False)


@pytest.fixture(scope="module")
def tracked() -> list[str]:
    out = git("ls-files")
    if out.returncode != 0:
        pytest.skip("not a git checkout (the docs are checked in the repository)")
    return out.stdout.split()


def ignored(path: str) -> bool:
    """A build output the repository's .gitignore names (`web/dist/`, `docs/site/_build/html`, `runs/...`)."""
    return git("check-ignore", "-q", "--no-index", path).returncode == 0


def missing_paths(tracked: list[str], md: str, text: str) -> list[str]:
    tops = {p.split("/")[0] for p in tracked}
    names = {p.rsplit("/", 1)[-1] for p in tracked}
    missing = []
    for m in NAMED.finditer(text):
        token = m.group(1) or m.group(2)
        path = re.sub(r"::.*$", "", token.rstrip(".,:;)")).rstrip("/")
        if not path or path.startswith(("http", "mailto", "-", "..")) or any(c in path for c in "*{}<>$=|…~"):
            continue
        if m.group(2):  # a link: relative to the Markdown file
            if not (ROOT / Path(md).parent / path).exists() and not (ROOT / path).exists():
                missing.append(token)
        elif "/" in path and path.split("/")[0] in tops:
            if not (ROOT / path).exists() and not ignored(path):
                missing.append(token)
        elif SOURCE.search(path):  # a source file named without its whole path
            tail = "/" + path if "/" in path else None
            if (path not in names if tail is None else not any(p.endswith(tail) for p in tracked)) and not ignored(
                path
            ):
                missing.append(token)
    return missing


def test_every_path_the_docs_name_exists(tracked):
    mds = [p for p in tracked if p.endswith(".md") and p not in HISTORY]
    assert "ARCHITECTURE.md" in mds and "docs/SPEC.md" in mds
    missing = {md: missing_paths(tracked, md, (ROOT / md).read_text()) for md in mds}
    missing = {md: paths for md, paths in missing.items() if paths}
    assert not missing, f"the docs name paths that do not exist: {missing}"


def test_a_missing_path_is_noticed(tracked):
    text = "see `observe.rs`, `crates/core/src/gone.rs`, [x](nowhere.md) and `crates/core/src/features.rs`"
    assert missing_paths(tracked, "ARCHITECTURE.md", text) == ["observe.rs", "crates/core/src/gone.rs", "nowhere.md"]


#: The last column of SPEC's table: what an option changes.
KIND = {True: "rules", False: "observation"}


def spec_table() -> str:
    rows = [
        f"| `{o['name']}` | `{o['default']}` | {o['allowed']} | {o['doc']} | {KIND[o['rule']]} |" for o in _core.OPTIONS
    ]
    return "\n".join(["| option | default | allowed | what it does | kind |", "|---|---|---|---|---|", *rows, ""])


def test_spec_lists_every_option_as_the_core_declares_it():
    spec = (ROOT / "docs" / "SPEC.md").read_text()
    assert spec_table() in spec, (
        f"docs/SPEC.md's table of options differs from the core's; it should read:\n{spec_table()}"
    )
