"""The 0.1 module paths that moved in 0.2.0 (`chopperscape.learn`, `chopperscape.integrations`): each still imports,
gives the new module's names, and warns (a `FutureWarning`) at the line that imported it; `python -m` on an old
path says where the command went and runs it. `collect(pilot=...)` is `collect(policy=...)`, with a warning."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys

import pytest

MOVED = {
    "chopperscape.train": "chopperscape.learn.train",
    "chopperscape.evaluate": "chopperscape.learn.evaluate",
    "chopperscape.seeds": "chopperscape.learn.seeds",
    "chopperscape.plot": "chopperscape.learn.plot",
    "chopperscape.export": "chopperscape.learn.export",
    "chopperscape.sb3": "chopperscape.integrations.sb3",
    "chopperscape.datasets": "chopperscape.integrations.datasets",
}


def _fresh(code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("old", sorted(MOVED))
def test_an_old_path_imports_the_new_module_and_warns_at_the_importer(old):
    new = MOVED[old]
    pytest.importorskip("torch") if ".learn." in new else None
    if old == "chopperscape.datasets":
        pytest.importorskip("minari")
    if old == "chopperscape.sb3":
        pytest.importorskip("stable_baselines3")
    code = (
        "import warnings, json\n"
        "warnings.simplefilter('always')\n"
        "with warnings.catch_warnings(record=True) as w:\n"
        f"    import {old} as m\n"
        f"import {new} as n\n"
        "print(json.dumps({'same': sorted(k for k in vars(n) if not k.startswith('__') and getattr(m, k) is not "
        "getattr(n, k)), 'warnings': [(x.category.__name__, str(x.message), x.filename, x.lineno) for x in w]}))\n"
    )
    out = _fresh(code)
    assert out.returncode == 0, out.stderr[-3000:]
    got = json.loads(out.stdout)
    assert got["same"] == [], f"{old} differs from {new} in {got['same']}"
    moved = [x for x in got["warnings"] if x[0] == "FutureWarning" and old in x[1]]
    assert len(moved) == 1, got["warnings"]
    _category, message, filename, lineno = moved[0]
    assert f"{old} moved to {new}" in message and "0.3.0" in message
    assert (filename, lineno) == ("<string>", 4), "the warning must point at the user's import line"


def test_the_old_train_module_still_holds_everything_0_1_had():
    pytest.importorskip("torch")
    with pytest.warns(FutureWarning, match="chopperscape.train moved to chopperscape.learn.train"):
        sys.modules.pop("chopperscape.train", None)
        old = importlib.import_module("chopperscape.train")
    from chopperscape.learn import model, recipe, train

    for name in ("Recipe", "PRESETS", "DEFAULT_STEPS", "check_recipe", "network_of"):
        assert getattr(old, name) is getattr(recipe, name), name
    for name in (
        "Agent",
        "CnnAgent",
        "ObsNormalizer",
        "RunningMeanStd",
        "agent_from_checkpoint",
        "build_agent",
        "save",
    ):
        assert getattr(old, name) is getattr(model, name), name
    assert old.train is train.train and old.main is train.main and old.CSV_COLUMNS == train.CSV_COLUMNS


def test_python_dash_m_on_an_old_path_says_where_it_went_and_runs_it():
    pytest.importorskip("torch")
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "chopperscape.evaluate",
            "heuristic",
            "--episodes",
            "2",
            "--seed",
            "5",
            "--option",
            "max_fuel=100",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr[-3000:]
    assert "python -m chopperscape.evaluate is now python -m chopperscape.learn.evaluate" in out.stderr
    new = subprocess.run(
        [
            sys.executable,
            "-m",
            "chopperscape.learn.evaluate",
            "heuristic",
            "--episodes",
            "2",
            "--seed",
            "5",
            "--option",
            "max_fuel=100",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert new.returncode == 0 and new.stderr == "", new.stderr
    assert json.loads(out.stdout) == json.loads(new.stdout)


def test_importing_the_package_or_its_new_paths_warns_nothing():
    code = (
        "import warnings\nwarnings.simplefilter('error')\n"
        "import chopperscape, chopperscape.policies, chopperscape.learn, chopperscape.integrations\n"
        "import chopperscape.learn.progress, chopperscape.learn.recipe\n"
        f"import sys\nassert not [m for m in sys.modules if m in {sorted(MOVED)!r}], 'an old path was imported'\n"
    )
    out = _fresh(code)
    assert out.returncode == 0, out.stderr[-3000:]


def test_collect_pilot_keyword_warns_and_is_the_policy_keyword(tmp_path, monkeypatch):
    pytest.importorskip("minari")
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path))
    from chopperscape.integrations import datasets

    with pytest.warns(FutureWarning, match=r"collect\(pilot=\.\.\.\) is now collect\(policy=\.\.\.\)"):
        old = datasets.collect(
            "test/old-kw-v0", pilot="random", episodes=1, seed=3, max_episode_steps=50, progress=False
        )
    new = datasets.collect("test/new-kw-v0", policy="random", episodes=1, seed=3, max_episode_steps=50, progress=False)
    assert old.storage.metadata["policy"] == new.storage.metadata["policy"] == "random"
    a, b = next(old.iterate_episodes()), next(new.iterate_episodes())
    assert a.actions.tolist() == b.actions.tolist()
