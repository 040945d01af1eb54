"""`Recipe.torch_compile` (`chopperscape.learn.compiled`): the network through torch.compile gives eager torch's
numbers and gradients, padding changes nothing, compiled runs are reproducible and resume, and the setting is
checked before anything is written."""

from __future__ import annotations

import json

import pytest
from conftest import needs_torch, pixel_recipe, progress_rows


def _recipe(**kw):
    return pixel_recipe(
        **{"env_options": {"obs_size": [20, 20], "frame_stack": 2, "max_fuel": 120}, "network": "small-coord", **kw}
    )


@needs_torch
def test_padding_cuts_back_to_the_batch_and_refuses_a_larger_one():
    import torch

    from chopperscape.learn.compiled import padded
    from chopperscape.learn.networks import build_agent

    torch.manual_seed(0)
    agent = build_agent("small-coord", (20, 20, 2))
    x = torch.randint(0, 256, (5, 20, 20, 2), dtype=torch.uint8)
    logits, value, h = padded(agent.heads, 9)(x)
    want = agent.heads(x)
    assert logits.shape == (5, 5) and value.shape == (5,) and h is not None and h.shape[0] == 5
    for got, exp in zip((logits, value, h), want):
        assert exp is not None
        torch.testing.assert_close(got, exp, rtol=1e-5, atol=1e-6)
    with pytest.raises(ValueError, match="larger than the compiled size 4"):
        padded(agent.heads, 4)(x)


@needs_torch
def test_eager_recipes_call_the_agent_itself():
    from chopperscape.learn.compiled import network_for
    from chopperscape.learn.networks import act_on, build_agent

    agent = build_agent("small", (20, 20, 2))
    net = network_for(_recipe(), agent)
    assert net.heads == agent.heads and net.act.func is act_on and net.act.args == (agent.heads,)


@needs_torch
def test_compiled_heads_give_eager_numbers_and_gradients():
    import torch

    from chopperscape.learn.compiled import network_for
    from chopperscape.learn.networks import act_on, build_agent

    torch.manual_seed(1)
    agent = build_agent("small-coord", (20, 20, 2), invert_frames=True)
    net = network_for(_recipe(torch_compile=True), agent)
    x = torch.randint(0, 256, (31, 20, 20, 2), dtype=torch.uint8)  # padded to the minibatch of 32

    def grads(heads):
        agent.zero_grad()
        logits, value, _ = heads(x)
        (torch.log_softmax(logits, -1)[:, 1].sum() + value.pow(2).sum()).backward()
        return [p.grad.clone() for p in agent.parameters()]

    eager, compiled = grads(agent.heads), grads(net.heads)
    for e, c in zip(eager, compiled):
        torch.testing.assert_close(c, e, rtol=1e-4, atol=1e-5)
    with torch.inference_mode():  # the rollout's batch: num_envs, sampled as ActorCritic.act samples
        obs = x[:4]
        torch.manual_seed(7)
        a_eager = act_on(agent.heads, obs)
        torch.manual_seed(7)
        a_comp = net.act(obs)
    assert len(a_comp) == 5 and torch.equal(a_eager[0], a_comp[0])  # the embedding too, for the novelty bonus
    for e, c in zip(a_eager[1:], a_comp[1:]):
        torch.testing.assert_close(c, e, rtol=1e-4, atol=1e-5)


@needs_torch
def test_compiled_runs_are_reproducible_resume_and_save_plain_models(tmp_path):
    import torch

    from chopperscape.learn import modelfile, train

    recipe = _recipe(torch_compile=True)
    train.train(recipe, tmp_path / "a")
    train.train(recipe, tmp_path / "b", until=4 * 16 * 2)
    train.train(recipe, tmp_path / "b", resume=True)
    a, b = (progress_rows(tmp_path / n / "progress.csv") for n in ("a", "b"))
    assert len(a) == 4
    drop = [{k: v for k, v in r.items() if k != "wall_s"} for r in a]
    assert drop == [{k: v for k, v in r.items() if k != "wall_s"} for r in b]
    assert all(r["value_loss"] not in ("", "nan") for r in a)
    assert json.loads((tmp_path / "a" / "recipe.json").read_text())["torch_compile"] is True
    # The saved model is the plain network: it loads and plays without compiling anything.
    loaded = modelfile.load(tmp_path / "a" / "model.pt")
    assert loaded.agent.heads(torch.zeros((2, 20, 20, 2), dtype=torch.uint8))[0].shape == (2, 5)


def test_the_setting_is_checked_before_anything_is_written(tmp_path, monkeypatch):
    from chopperscape.learn import flags
    from chopperscape.learn.recipe import Recipe, check_recipe

    with pytest.raises(ValueError, match="compiling is for CNN recipes"):
        check_recipe(Recipe(torch_compile=True))
    with pytest.raises(ValueError, match="option `torch_compile`"):
        check_recipe(_recipe(torch_compile="yes"))
    monkeypatch.setenv("CXX", "no-such-compiler-here")
    with pytest.raises(ValueError, match=r"'no-such-compiler-here' \(from CXX\) is not on PATH.*--no-torch-compile"):
        check_recipe(_recipe(torch_compile=True))
    with pytest.raises(SystemExit) as e:
        flags.parse(["--preset", "pixels", "--torch-compile", "--out", str(tmp_path / "x")])
    assert e.value.code == 2 and not (tmp_path / "x").exists()
    monkeypatch.delenv("CXX")
    _, recipe = flags.parse(["--preset", "pixels", "--no-torch-compile", "--out", str(tmp_path / "y")])
    assert recipe.torch_compile is False


def test_older_run_folders_still_resume():
    """A setting added later is left out of the recipe's hash at the value older runs had, so a resume.pt
    written before it existed still matches its recipe.json."""
    from dataclasses import asdict

    from chopperscape.learn.recipe import Recipe
    from chopperscape.learn.rundir import recipe_hash

    old = {k: v for k, v in asdict(Recipe()).items() if k != "torch_compile"}
    assert recipe_hash(Recipe()) == recipe_hash(old)
    assert recipe_hash(Recipe(obs_type="grayscale", torch_compile=True)) != recipe_hash(Recipe(obs_type="grayscale"))


def test_phases_count_each_first_call_apart():
    """Where a compiled network compiles (its first call) is not its cost per step: the stopwatch keeps it apart,
    and the loop's time still adds up."""
    import time

    from chopperscape.learn.phases import Phases

    phases = Phases()
    phases.start()
    sleep = phases.timed("env", time.sleep)
    for seconds in (0.05, 0.0, 0.0):
        sleep(seconds)
    phases.finish(3)
    assert phases.first["env"] >= 0.05 and phases.seconds["env"] < 0.05
    assert phases.seconds["bookkeeping"] < 0.05
