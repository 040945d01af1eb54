"""The training state (`chopperscape.learn.state.TrainState`) saves and restores itself field by field: a new field
round-trips through `resume.pt` with no change to the loop or the checkpoint code, every field of a real run comes
back as it was, and a state that lacks a field or belongs to another run is refused by name."""

from __future__ import annotations

import shutil
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pytest
from conftest import needs_torch

pytestmark = needs_torch


class Visits:
    """A part with a state of its own, as a new training feature would bring."""

    def __init__(self) -> None:
        self.counts = {"fuel": 0}

    def state_dict(self) -> dict[str, Any]:
        return dict(self.counts)

    def load_state_dict(self, s: dict[str, Any]) -> None:
        self.counts = dict(s)


def _with_fields():
    from chopperscape.learn.state import TrainState

    @dataclass
    class WithFields(TrainState):
        visits: Visits = field(default_factory=Visits)
        seen: np.ndarray = field(default_factory=lambda: np.zeros(3))
        best: float = 0.0

    return WithFields


def _equal(a: Any, b: Any) -> bool:
    import torch

    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_equal(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(_equal(x, y) for x, y in zip(a, b))
    if isinstance(a, torch.Tensor):
        return torch.equal(a, b)
    return a == b


def _recipe():
    from chopperscape.learn.recipe import Recipe

    return Recipe(num_envs=4, num_steps=16, hidden=8, num_minibatches=2, total_steps=4 * 16 * 3)


def test_a_new_field_round_trips_without_touching_the_loop(tmp_path, monkeypatch):
    import torch

    from chopperscape.learn import run, train

    monkeypatch.setattr(run, "TrainState", _with_fields())
    recipe = _recipe()
    train.train(recipe, tmp_path)  # the loop, unchanged, carries the new fields through its checkpoints
    saved = torch.load(tmp_path / "resume.pt", weights_only=True)["state"]
    assert saved["visits"] == {"fuel": 0} and saved["best"] == 0.0 and saved["seen"].tolist() == [0.0] * 3
    with run.Run(recipe, tmp_path, resume=True) as r:
        r.state.visits.counts["fuel"] = 7
        r.state.seen = np.array([1.0, 2.0, 3.0])
        r.state.best = 9.5
        before = r.state.state_dict()
    with run.Run(recipe, tmp_path, resume=True) as again:
        assert again.state.visits.counts == {"fuel": 7}
        assert again.state.seen.tolist() == [1.0, 2.0, 3.0] and again.state.best == 9.5
        after = again.state.state_dict()
    # Every field of the run, networks, optimiser, normalisers, envs, random streams and counters, came back.
    assert before.keys() == after.keys()
    for name in before:
        if name != "clock":
            assert _equal(before[name], after[name]), name


def test_two_resumes_of_one_state_draw_the_same_numbers_and_step_the_same_envs(tmp_path):
    import torch

    from chopperscape.learn import run, train

    train.train(_recipe(), tmp_path / "run")
    draws = []
    for copy in ("x", "y"):  # leaving a run saves it again: each resume starts from its own copy of the folder
        shutil.copytree(tmp_path / "run", tmp_path / copy)
        with run.Run(_recipe(), tmp_path / copy, resume=True) as r:
            obs = r.envs.step(np.ones(4, np.int64))[0]
            draws.append((torch.rand(3), r.state.rng.random(3), obs, r.state.next_obs.clone()))
    (a, b) = draws
    assert torch.equal(a[0], b[0]) and np.array_equal(a[1], b[1]) and np.array_equal(a[2], b[2])
    assert torch.equal(a[3], b[3])


def test_a_state_without_a_field_or_from_another_run_is_refused_by_name(tmp_path, monkeypatch):
    from chopperscape.learn import run, train

    recipe = _recipe()
    train.train(recipe, tmp_path / "a")
    with monkeypatch.context() as m:
        m.setattr(run, "TrainState", _with_fields())
        with pytest.raises(ValueError, match=r"resume\.pt does not fit this run's recipe \(it holds no `visits`\)"):
            run.Run(recipe, tmp_path / "a", resume=True)
    # Another run's resume.pt (another seed and learning rate, same shapes) is refused: it names its recipe.
    train.train(replace(recipe, seed=5, learning_rate=1e-3), tmp_path / "b")
    shutil.copy(tmp_path / "b" / "resume.pt", tmp_path / "a" / "resume.pt")
    with pytest.raises(ValueError, match="belongs to another run"):
        run.Run(recipe, tmp_path / "a", resume=True)
