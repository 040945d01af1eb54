"""The deprecated module `chopperscape.pilots` (renamed `chopperscape.policies`, issue 18): importing it warns,
and its old names still work.
"""

from __future__ import annotations

import importlib
import subprocess
import sys

import gymnasium as gym
import pytest

import chopperscape
from chopperscape import policies

MESSAGE = (
    "chopperscape.pilots is deprecated: use chopperscape.policies (Pilot -> Policy, VectorPilot -> VectorPolicy; "
    "it goes away in 0.3.0)"
)


def _import_pilots():
    """Imports (or re-imports) `chopperscape.pilots`, returning the module; the warning goes to the caller."""
    if "chopperscape.pilots" in sys.modules:
        return importlib.reload(sys.modules["chopperscape.pilots"])
    return importlib.import_module("chopperscape.pilots")


def test_importing_the_old_module_warns_deprecation():
    with pytest.warns(FutureWarning) as record:
        _import_pilots()
    messages = [str(w.message) for w in record if issubclass(w.category, FutureWarning)]
    assert messages == [MESSAGE]


def test_the_warning_points_at_the_importer():
    # In a fresh interpreter, so that the module is really imported; the warning's location is the `import` line.
    code = (
        "import warnings\n"
        "warnings.simplefilter('always')\n"
        "with warnings.catch_warnings(record=True) as w:\n"
        "    from chopperscape import pilots\n"
        "print(len(w), w[0].category.__name__, w[0].filename, w[0].lineno)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split() == ["1", "FutureWarning", "<string>", "4"], out.stdout


def test_the_old_names_still_work():
    with pytest.warns(FutureWarning, match="chopperscape.pilots is deprecated"):
        pilots = _import_pilots()
    assert pilots.Pilot is policies.Policy and pilots.VectorPilot is policies.VectorPolicy
    assert pilots.Policy is policies.Policy and pilots.VectorPolicy is policies.VectorPolicy
    for name in ("NAMES", "make", "random", "heuristic", "fixed", "episodes"):
        assert getattr(pilots, name) is getattr(policies, name), name
    assert set(pilots.__all__) >= set(policies.__all__) | {"Pilot", "VectorPilot"}

    env = gym.make("ChopperScape-v0", obs_type="features")
    env.reset(seed=0)
    old, new = pilots.Pilot("random", 3), policies.Policy("random", 3)
    assert [old.act(env) for _ in range(20)] == [new.act(env) for _ in range(20)]
    envs = chopperscape.VectorEnv(2, obs_type="features")
    envs.reset(seed=0)
    old_batch, new_batch = pilots.VectorPilot("heuristic", 2), policies.VectorPolicy("heuristic", 2)
    assert old_batch.act(envs).tolist() == new_batch.act(envs).tolist()
    old_eps = [e["return"] for e in pilots.episodes("heuristic", 2, 0, max_episode_steps=200)]
    assert old_eps == [e["return"] for e in policies.episodes("heuristic", 2, 0, max_episode_steps=200)]


def test_the_compiled_module_keeps_no_old_name():
    # Only the Python shim keeps the old names; `chopperscape._core` has `Policy`, `VectorPolicy`, `POLICY_NAMES`.
    assert not [name for name in dir(chopperscape._core) if "pilot" in name.lower()]


def test_importing_chopperscape_does_not_import_the_old_module():
    assert "pilots" not in chopperscape.__all__
    # A fresh interpreter that turns warnings into errors: `import chopperscape` must not touch the old module.
    code = "import sys, chopperscape; assert 'chopperscape.pilots' not in sys.modules, sorted(sys.modules)"
    out = subprocess.run([sys.executable, "-W", "error", "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
