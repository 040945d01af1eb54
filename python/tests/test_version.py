"""One version number: the workspace's crates, the Python packages (built and installed) and the changelog agree."""

from __future__ import annotations

import re
from importlib import metadata
from pathlib import Path

import pytest

import chopperscape

tomllib = pytest.importorskip("tomllib")  # Python >= 3.11; the test environments have it

ROOT = Path(__file__).resolve().parents[2]


def toml(path: Path) -> dict:
    return tomllib.loads(path.read_text(encoding="utf-8"))


def workspace_version() -> str:
    return toml(ROOT / "Cargo.toml")["workspace"]["package"]["version"]


def test_every_crate_takes_the_workspace_version():
    version = workspace_version()
    assert re.fullmatch(r"\d+\.\d+\.\d+", version), version
    crates = sorted((ROOT / "crates").glob("*/Cargo.toml"))
    assert len(crates) >= 6
    for manifest in crates:
        package = toml(manifest)["package"]
        assert package["version"] in ({"workspace": True}, version), f"{manifest}: version {package['version']!r}"


@pytest.mark.parametrize("pyproject", ["python/pyproject.toml", "python/cli/pyproject.toml"])
def test_python_packages_take_the_crates_version(pyproject):
    project = toml(ROOT / pyproject)["project"]
    # maturin fills the version in from the crate's Cargo.toml, i.e. the workspace's.
    assert "version" not in project and "version" in project["dynamic"], pyproject


def test_the_cli_extra_pins_the_same_version():
    extras = toml(ROOT / "python/pyproject.toml")["project"]["optional-dependencies"]
    assert extras["cli"] == [f"chopperscape-cli=={workspace_version()}"]


def test_the_installed_package_has_the_workspace_version():
    assert chopperscape.__version__ == workspace_version()
    assert metadata.version("chopperscape") == workspace_version()


def test_the_latest_release_in_the_changelog_is_this_version():
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    releases = re.findall(r"^## \[(\d+\.\d+\.\d+)\] - (\d{4}-\d{2}-\d{2})$", text, flags=re.MULTILINE)
    assert releases, "CHANGELOG.md has no release heading '## [X.Y.Z] - YYYY-MM-DD'"
    assert releases[0][0] == workspace_version()
    headings = re.findall(r"^## \[([^\]]+)\]", text, flags=re.MULTILINE)
    assert headings[0] == "Unreleased" and headings[1] == releases[0][0]


def test_no_placeholder_address_is_shipped():
    # The project has no public home yet: no metadata, README or changelog may point at a made-up one (add the real
    # addresses, and the changelog's compare links, when there is one).
    for name in (
        "Cargo.toml",
        "CHANGELOG.md",
        "python/pyproject.toml",
        "python/cli/pyproject.toml",
        "python/cli/README.md",
        "python/README.md",
        "README.md",
    ):
        text = (ROOT / name).read_text(encoding="utf-8")
        assert "example.invalid" not in text and "example.com" not in text, f"{name} has a placeholder address"


def test_the_packages_ship_the_repository_license():
    # maturin takes a package's license file from beside its pyproject.toml, so the repository's LICENSE is copied.
    license_text = (ROOT / "LICENSE").read_bytes()
    for copy in ("python/LICENSE", "python/cli/LICENSE"):
        assert (ROOT / copy).read_bytes() == license_text, f"{copy} differs from LICENSE"
    for pyproject in ("python/pyproject.toml", "python/cli/pyproject.toml"):
        project = toml(ROOT / pyproject)["project"]
        assert project["license"] == toml(ROOT / "Cargo.toml")["workspace"]["package"]["license"], pyproject
