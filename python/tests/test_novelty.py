"""`--rnd-coef`: the exploration bonus from the frames alone (`chopperscape.learn.novelty`, Random Network
Distillation). The bonus is the predictor's error on the latest frame, larger on frames it has not learned, 0 on
reset steps; the predictor trains, the run resumes (tests/test_resume.py) and saves the same kind of policy; the
networks leave torch's random stream as it is; the setting is refused where it means nothing. `--rnd-own-value`:
the bonus as a reward of its own, its advantage (with its own value head) not cut at episode ends and joined to the
game's."""

from __future__ import annotations

import importlib.util
import json
from dataclasses import replace

import numpy as np
import pytest
from conftest import pixel_recipe

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("torch") is None, reason="torch is not installed (scripts/test-python.sh installs it)"
)


def _recipe(**kw):
    return pixel_recipe(**{"total_steps": 4 * 16 * 6, **kw})


def _frames(n: int, row: int, stack: int = 2) -> np.ndarray:
    """`n` stacks of white 16×16 frames with a black bar across `row` in the latest one."""
    x = np.full((n, 16, 16, stack), 255, np.uint8)
    x[:, row : row + 3, :, -1] = 0
    return x


def test_the_bonus_is_larger_on_frames_the_predictor_has_not_learned_and_0_on_reset_steps():
    import torch

    from chopperscape.learn.novelty import RandomDistillation

    rnd = RandomDistillation(0.5, (16, 16, 2), num_envs=8, seed=3, device="cpu")
    optimizer = torch.optim.Adam(rnd.params, lr=1e-3)
    seen, unseen = _frames(8, 2), _frames(8, 11)
    valid = np.ones(8, bool)
    for _ in range(4):  # the statistics see both kinds of frame; the predictor learns only the first
        rnd.bonus(0, None, seen, valid), rnd.bonus(0, None, unseen, valid)
    for _ in range(200):
        loss, row = rnd.loss(torch.from_numpy(seen), None, torch.arange(8))
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
    assert set(row) == {"rnd_loss", "novelty"} and row["rnd_loss"] < 0.01
    known, new = rnd.bonus(1, None, seen, valid), rnd.bonus(2, None, unseen, valid)
    assert known.dtype == np.float32 and known.shape == (8,)
    assert (new > 10 * known).all() and (known > 0).all()
    valid[[1, 5]] = False  # reset steps: no bonus, and the running sums stay
    before = rnd.running.copy()
    out = rnd.bonus(3, None, unseen, valid)
    assert out[1] == 0 and out[5] == 0 and (out[valid] > 0).all()
    assert rnd.running[1] == before[1] and rnd.running[0] != before[0]


def test_the_bonus_reads_only_the_latest_frame_and_its_weight_scales_it():
    from chopperscape.learn.novelty import RandomDistillation

    a = RandomDistillation(1.0, (16, 16, 2), num_envs=4, seed=3, device="cpu")
    b = RandomDistillation(2.0, (16, 16, 2), num_envs=4, seed=3, device="cpu")
    x = _frames(4, 6)
    y = x.copy()
    y[..., 0] = 0  # another older frame: the same bonus
    valid = np.ones(4, bool)
    out_a, out_b = a.bonus(0, None, x, valid), b.bonus(0, None, y, valid)
    assert np.allclose(2 * out_a, out_b)
    single = RandomDistillation(1.0, (16, 16), num_envs=4, seed=3, device="cpu")  # no stack axis
    assert np.allclose(single.bonus(0, None, x[..., -1], valid), out_a)


def test_pooled_the_bonus_is_the_bonus_of_the_pooled_frame():
    """`rnd_pool` 2 on 32×32 frames is the plain bonus on their 16×16 halves: the same networks (drawn for the
    pooled size), statistics, errors and predictor loss; older frames still unread. A frame too small once pooled
    is refused, naming the pooling."""
    import torch

    from chopperscape.learn.novelty import RandomDistillation

    big = RandomDistillation(1.0, (32, 32, 2), num_envs=4, seed=3, device="cpu", pool=2)
    small = RandomDistillation(1.0, (16, 16, 2), num_envs=4, seed=3, device="cpu")
    rng = np.random.default_rng(0)
    valid = np.array([True, True, False, True])
    for t in range(3):
        x = rng.integers(1, 255, (4, 16, 16, 2), dtype=np.uint8)
        wide = x.repeat(2, axis=1).repeat(2, axis=2)  # each pixel a 2×2 square: pooling gives `x` back exactly,
        wide[:, ::2, ::2, -1] += 1  # though each square's four pixels differ (their mean is still `x`'s)
        wide[:, 1::2, 1::2, -1] -= 1
        wide[..., 0] = rng.integers(0, 256, (4, 32, 32))  # older frames: anything
        assert np.array_equal(big.bonus(t, None, wide, valid), small.bonus(t, None, x, valid))
    assert np.array_equal(big.frames.mean, small.frames.mean) and np.array_equal(big.running, small.running)
    loss_big, _ = big.loss(torch.from_numpy(wide), None, torch.arange(4))
    loss_small, _ = small.loss(torch.from_numpy(x), None, torch.arange(4))
    assert torch.equal(loss_big, loss_small)
    with pytest.raises(ValueError, match=r"16×16, 2×2 pixels averaged into one, are too small .* after pooling"):
        RandomDistillation(1.0, (16, 16, 2), num_envs=2, seed=0, device="cpu", pool=2)


def test_making_the_networks_leaves_torchs_random_stream_as_it_is():
    import torch

    from chopperscape.learn.novelty import RandomDistillation

    torch.manual_seed(7)
    expected = torch.rand(3)
    torch.manual_seed(7)
    a = RandomDistillation(1.0, (16, 16, 2), num_envs=2, seed=0, device="cpu")
    assert torch.equal(torch.rand(3), expected)
    b = RandomDistillation(1.0, (16, 16, 2), num_envs=2, seed=0, device="cpu")
    c = RandomDistillation(1.0, (16, 16, 2), num_envs=2, seed=1, device="cpu")
    weights = [m[0].weight for m in (a.target, b.target, c.target)]
    assert torch.equal(weights[0], weights[1]) and not torch.equal(weights[0], weights[2])
    assert not a.target[0].weight.requires_grad and all(p.requires_grad for p in a.params)


def test_a_run_with_it_logs_it_and_saves_the_same_kind_of_policy(tmp_path):
    import csv

    import torch

    from chopperscape.learn import train

    plain = train.train(_recipe(), tmp_path / "plain")
    rnd = train.train(_recipe(rnd_coef=0.5), tmp_path / "rnd")
    with open(tmp_path / "rnd" / "progress.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    losses, novelty = [float(r["rnd_loss"]) for r in rows], [float(r["novelty"]) for r in rows]
    # Finite and positive (that the predictor learns is the first test's: here new sprites keep appearing).
    assert len(rows) == 6 and all(0 < v < 1e3 for v in losses + novelty)
    with open(tmp_path / "plain" / "progress.csv", newline="") as f:
        assert all(r["rnd_loss"] == "" and r["novelty"] == "" for r in csv.DictReader(f))
    a, b = torch.load(plain, weights_only=True), torch.load(rnd, weights_only=True)
    assert set(a) == set(b) and set(a["actor"]) == set(b["actor"])  # no RND networks in the policy file
    assert not all(torch.equal(a["actor"][k], b["actor"][k]) for k in a["actor"])  # the bonus changed learning
    assert json.loads((tmp_path / "rnd" / "recipe.json").read_text())["rnd_coef"] == 0.5


def test_it_is_refused_where_it_means_nothing_before_anything_is_written(tmp_path):
    from chopperscape.learn import train
    from chopperscape.learn.novelty import NoNovelty, RandomDistillation
    from chopperscape.learn.recipe import Recipe, check_recipe

    with pytest.raises(ValueError, match=r"`rnd_coef`: the novelty bonus is for CNN recipes"):
        train.train(Recipe(rnd_coef=1.0), tmp_path / "a")
    with pytest.raises(ValueError, match=r"rnd_coef"):
        train.train(_recipe(rnd_coef=-1.0), tmp_path / "b")
    with pytest.raises(ValueError, match=r"too small for the novelty bonus"):
        RandomDistillation(1.0, (8, 8, 2), num_envs=2, seed=0, device="cpu")
    for pool in (3, 2.0, True):  # a pool from a recipe file: a power of two, and a whole number
        with pytest.raises(ValueError, match=r"`rnd_pool`: allowed 1, 2, 4"):
            check_recipe(replace(_recipe(rnd_coef=0.5), rnd_pool=pool))
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()
    rnd = RandomDistillation(1.0, (16, 16, 2), num_envs=2, seed=0, device="cpu")
    with pytest.raises(ValueError, match="holds a novelty bonus"):
        NoNovelty().load_state_dict(rnd.state_dict())
    with pytest.raises(ValueError, match="holds no novelty bonus"):
        rnd.load_state_dict(None)
    with pytest.raises(ValueError, match="sums of"):
        RandomDistillation(1.0, (16, 16, 2), num_envs=3, seed=0, device="cpu").load_state_dict(rnd.state_dict())


def _own(**settings):
    """A recipe with the bonus's own value, its agent, and the part."""
    from chopperscape.learn.networks import build_agent
    from chopperscape.learn.novelty import novelty_of

    recipe = _recipe(rnd_coef=0.5, rnd_own_value=True, **settings)
    agent = build_agent("small", (16, 16, 2), invert_frames=True)
    return recipe, agent, novelty_of(recipe, (16, 16, 2), "cpu", agent)


def test_its_own_value_keeps_the_bonus_apart_from_the_games_reward():
    import torch

    from chopperscape.learn.novelty import OwnValueDistillation, RandomDistillation

    recipe, _, own = _own()
    assert isinstance(own, OwnValueDistillation)
    valid = np.array([True, False, True, True])
    h = torch.randn(4, 256)  # the embedding the policy acted on, from the rollout's own forward pass
    out = own.bonus(5, h, _frames(4, 3), valid)
    assert out.dtype == np.float32 and out.shape == (4,) and not out.any()  # nothing added to the game's reward
    assert not own.rewards.any()  # taken for the rollout at once, when its advantages are
    own.settle()
    assert own.rewards[5, 1] == 0 and (own.rewards[5, valid] > 0).all() and not own.rewards[4].any()
    with torch.no_grad():  # its value read from that embedding: no second pass of the trunk
        assert torch.equal(own.values[5], own.value_head(h).squeeze(-1)) and not own.values[4].any()
    one_head = RandomDistillation(0.5, (16, 16, 2), num_envs=4, seed=recipe.seed, device="cpu")
    assert np.allclose(one_head.bonus(5, None, _frames(4, 3), valid), 0.5 * own.rewards[5].numpy())


def test_its_own_bonus_taken_a_rollout_at_once_is_the_step_by_step_bonus(monkeypatch):
    """The errors of a rollout's frames in one pass (in calls of `CHUNK` frames), each step's scale in order: the
    plain bonus's numbers step by step (to float32 rounding), its frame statistics, running sums and scale the same;
    a second rollout goes on from the first's."""
    import torch

    from chopperscape.learn import novelty
    from chopperscape.learn.novelty import RandomDistillation

    recipe, _, own = _own(num_envs=4, num_steps=6)
    plain = RandomDistillation(0.5, (16, 16, 2), num_envs=4, seed=recipe.seed, device="cpu")
    rng = np.random.default_rng(7)
    h = torch.zeros(4, 256)
    monkeypatch.setattr(novelty, "CHUNK", 5)  # more than one call a rollout
    for rollout in range(2):
        steps = []
        for t in range(6):
            raw = rng.integers(0, 256, (4, 16, 16, 2), dtype=np.uint8)
            valid = rng.random(4) < 0.8
            steps.append(plain.scaled(raw, valid))
            own.bonus(t, h, raw, valid)
        assert own.pending == 6 and (rollout or not own.rewards.any())
        own.settle()
        assert own.pending == 0
        assert np.allclose(own.rewards.numpy(), np.array(steps, np.float32), rtol=1e-5, atol=1e-7)
        assert np.array_equal(own.frames.mean, plain.frames.mean) and np.allclose(own.running, plain.running)
        assert np.isclose(own.errors.var, plain.errors.var) and own.since[1] == plain.since[1]


def test_its_own_advantage_runs_across_episode_ends_and_joins_the_games():
    """By hand: the bonus's value 1 everywhere, rewards 1..7; env 0's episode ends at row 1 (row 2 is its reset
    step), and its advantage there still reads row 3's, the next episode's first step."""
    import torch

    from chopperscape.learn.rollout import Rollout, advantages

    _, agent, own = _own(num_envs=2, num_steps=4, gae_lambda=0.5)
    buf = Rollout(4, 2, (16, 16, 2), torch.uint8, "cpu")
    valid = np.array([[1, 1], [1, 1], [0, 1], [1, 1]], bool)
    for t in range(4):
        zeros = torch.zeros(2)
        buf.store(t, torch.from_numpy(_frames(2, 3 * t)), zeros.long(), zeros, zeros, valid[t])
        buf.outcome(t, np.ones(2, np.float32), np.array([t == 1, False]))
    rewards = torch.tensor([[1.0, 2.0], [3.0, 4.0], [0.0, 5.0], [6.0, 7.0]])
    with torch.no_grad():  # next_obs's value from the head; the rollout's, as its steps stored them
        own.value_head.weight.zero_()
        own.value_head.bias.fill_(1.0)
    own.rewards.copy_(rewards)
    own.values.fill_(1.0)
    next_obs = torch.from_numpy(_frames(2, 12))
    game = advantages(buf, agent, next_obs, 0.998, 0.5)
    joined = own.advantages(game, buf, next_obs)
    g, gl = 0.99, 0.99 * 0.5
    d = (rewards + g - 1).tolist()  # each step's error, bootstrapped from a value of 1 (next_obs's too)
    env0 = [d[3][0]]
    for t in (1, 0):  # row 2 is skipped, not cut
        env0.insert(0, d[t][0] + gl * env0[0])
    env1 = [d[3][1]]
    for t in (2, 1, 0):
        env1.insert(0, d[t][1] + gl * env1[0])
    expected = torch.tensor([env0[0], env1[0], env0[1], env1[1], env1[2], env0[2], env1[3]])  # rows, then envs
    assert torch.allclose(joined.advantages - game.advantages, 0.5 * expected)
    assert torch.allclose(own.returns, expected + 1)
    assert torch.equal(joined.returns, game.returns) and torch.equal(joined.obs, game.obs)


def test_a_run_with_its_own_value_trains_and_resumes_only_its_own_kind(tmp_path):
    import csv

    import torch

    from chopperscape.learn import train
    from chopperscape.learn.novelty import RandomDistillation

    one = train.train(_recipe(rnd_coef=0.5), tmp_path / "one")
    own = train.train(_recipe(rnd_coef=0.5, rnd_own_value=True), tmp_path / "own")
    with open(tmp_path / "own" / "progress.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 6 and all(0 < float(r["rnd_loss"]) < 1e3 and float(r["value_loss"]) < 1e3 for r in rows)
    a, b = torch.load(one, weights_only=True), torch.load(own, weights_only=True)
    assert set(a) == set(b) and set(a["actor"]) == set(b["actor"])  # no value head of the bonus's in the policy
    assert not all(torch.equal(a["actor"][k], b["actor"][k]) for k in a["actor"])
    state = torch.load(tmp_path / "own" / "resume.pt", weights_only=True)["state"]["novelty"]
    head = state["value_head"]
    assert head["weight"].shape == (1, 256) and head["bias"].abs().item() > 0  # it learned
    _, _, part = _own()
    part.load_state_dict(state)
    assert torch.equal(part.value_head.weight, head["weight"])
    one_head = RandomDistillation(0.5, (16, 16, 2), num_envs=4, seed=0, device="cpu")
    with pytest.raises(ValueError, match="has a value head of its own"):
        one_head.load_state_dict(state)
    with pytest.raises(ValueError, match="has no value head of its own"):
        part.load_state_dict(one_head.state_dict())


def test_its_own_value_is_refused_without_the_bonus(tmp_path):
    from chopperscape.learn import train

    with pytest.raises(ValueError, match=r"`rnd_own_value`: it is the novelty bonus's; allowed with rnd_coef > 0"):
        train.train(_recipe(rnd_own_value=True), tmp_path / "a")
    assert not (tmp_path / "a").exists()


def test_its_predictor_learns_from_the_given_share_of_each_minibatch(tmp_path):
    import torch

    from chopperscape.learn import train
    from chopperscape.learn.novelty import RandomDistillation

    whole = RandomDistillation(0.5, (16, 16, 2), num_envs=4, seed=3, device="cpu")
    quarter = RandomDistillation(0.5, (16, 16, 2), num_envs=4, seed=3, device="cpu", proportion=0.25)
    x = torch.from_numpy(np.concatenate([_frames(3, 2), _frames(9, 11)]))
    rows = torch.arange(12)
    with torch.no_grad():
        assert torch.equal(whole.loss(x, None, rows)[0], whole._error(x).mean())
        assert torch.equal(quarter.loss(x, None, rows)[0], whole._error(x[:3]).mean())  # the first 3 of 12 rows
        assert not torch.equal(quarter.loss(x, None, rows)[0], whole.loss(x, None, rows)[0])
        tiny = RandomDistillation(0.5, (16, 16, 2), num_envs=4, seed=3, device="cpu", proportion=0.01)
        assert torch.equal(tiny.loss(x, None, rows)[0], whole._error(x[:1]).mean())  # at least one row
    with pytest.raises(ValueError, match=r"`rnd_proportion`: it is the novelty bonus's; allowed with rnd_coef > 0"):
        train.train(_recipe(rnd_proportion=0.25), tmp_path / "a")
    for bad in (0.0, 1.5, float("nan")):
        with pytest.raises(ValueError, match=r"`rnd_proportion`"):
            train.train(_recipe(rnd_coef=0.5, rnd_proportion=bad), tmp_path / "b")
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_its_weight_falls_to_its_floor_over_the_schedule():
    """`rnd_floor`: the weight falls linearly over the step budget to the floor's share of `rnd_coef`, as the
    entropy's does; the default floor keeps the weight exactly, so the runs before it train bit for bit as they did.
    The part takes the weight the loop schedules: the one-head bonus and the own value's joined advantage scale with
    it."""
    import torch

    from chopperscape.learn.novelty import RandomDistillation, novelty_of, novelty_weight
    from chopperscape.learn.recipe import Recipe, check_recipe
    from chopperscape.learn.rollout import Rollout, advantages

    assert [novelty_weight(0.5, 1.0, t, 1000) for t in (0, 500, 1000, 2000)] == [0.5] * 4
    assert [novelty_weight(0.5, 0.0, t, 1000) for t in (0, 500, 1000, 2000)] == pytest.approx([0.5, 0.25, 0.0, 0.0])
    assert novelty_weight(0.5, 0.2, 500, 1000) == pytest.approx(0.3)
    a = RandomDistillation(0.5, (16, 16, 2), num_envs=4, seed=3, device="cpu", floor=0.0, total_steps=1000)
    b = RandomDistillation(0.5, (16, 16, 2), num_envs=4, seed=3, device="cpu")
    valid = np.ones(4, bool)
    a.schedule(750)
    assert a.weight == pytest.approx(0.125)
    assert np.allclose(a.bonus(0, None, _frames(4, 6), valid), 0.25 * b.bonus(0, None, _frames(4, 6), valid))
    a.schedule(1000)
    assert not a.bonus(1, None, _frames(4, 9), valid).any()

    recipe, agent, own = _own(rnd_floor=0.25)
    assert own.floor == 0.25 and own.total_steps == recipe.total_steps
    own.schedule(recipe.total_steps)
    assert own.weight == pytest.approx(0.125)
    constant = novelty_of(replace(recipe, rnd_floor=1.0), (16, 16, 2), "cpu", agent)  # the same agent and networks
    for part in (own, constant):  # the same rollout for both: one step of new frames, valid
        part.bonus(0, torch.zeros(4, 256), _frames(4, 3), valid)
    buf = Rollout(recipe.num_steps, 4, (16, 16, 2), torch.uint8, "cpu")
    for t in range(recipe.num_steps):
        zeros = torch.zeros(4)
        buf.store(t, torch.from_numpy(_frames(4, t % 13)), zeros.long(), zeros, zeros, valid)
        buf.outcome(t, np.ones(4, np.float32), np.zeros(4, bool))
    next_obs = torch.from_numpy(_frames(4, 12))
    game = advantages(buf, agent, next_obs, 0.998, 0.95)
    low, full = own.advantages(game, buf, next_obs), constant.advantages(game, buf, next_obs)
    assert not torch.equal(full.advantages, game.advantages)
    assert torch.allclose(low.advantages - game.advantages, 0.25 * (full.advantages - game.advantages), atol=1e-6)

    for bad in (-0.1, 1.5, float("nan")):
        with pytest.raises(ValueError, match=r"`rnd_floor`"):
            check_recipe(Recipe(obs_type="grayscale", network="small", rnd_coef=0.5, rnd_floor=bad))
    with pytest.raises(ValueError, match=r"`rnd_floor`: it is the novelty bonus's; allowed with rnd_coef > 0"):
        check_recipe(Recipe(obs_type="grayscale", network="small", rnd_floor=0.5))


def test_its_weight_holds_before_it_falls():
    """`rnd_hold`: the weight stays at `rnd_coef` over the first share of the budget, then falls linearly over the
    rest to its floor; the default hold of 0 is the whole budget's fall, exactly. The part and the recipe's checks
    take it: refused outside [0, 1), and without a floor below 1 (nothing would fall) or without the bonus."""
    from chopperscape.learn.novelty import RandomDistillation, novelty_weight
    from chopperscape.learn.recipe import Recipe, check_recipe

    held = [novelty_weight(0.5, 0.0, t, 1000, 0.5) for t in (0, 250, 500, 750, 1000, 2000)]
    assert held == pytest.approx([0.5, 0.5, 0.5, 0.25, 0.0, 0.0])
    assert novelty_weight(0.5, 0.2, 800, 1000, 0.6) == pytest.approx(0.5 * (1 - 0.8 * 0.5))
    for t in range(0, 1200, 37):  # hold 0 is the earlier fall, float for float
        assert novelty_weight(0.5, 0.3, t, 1000, 0.0) == novelty_weight(0.5, 0.3, t, 1000)
    part = RandomDistillation(0.5, (16, 16, 2), num_envs=4, seed=3, device="cpu", floor=0.0, total_steps=1000, hold=0.5)
    part.schedule(400)
    assert part.weight == 0.5
    part.schedule(900)
    assert part.weight == pytest.approx(0.1)
    recipe, _, own = _own(rnd_floor=0.0, rnd_hold=0.5)
    own.schedule(recipe.total_steps * 3 // 4)
    assert own.hold == 0.5 and own.weight == pytest.approx(0.25)

    bonus = {"obs_type": "grayscale", "network": "small", "rnd_coef": 0.5}
    for bad in (-0.1, 1.0, 2.0, float("nan"), float("inf"), True):
        with pytest.raises(ValueError, match=r"`rnd_hold`: allowed a finite number in \[0, 1\)"):
            check_recipe(Recipe(**bonus, rnd_floor=0.0, rnd_hold=bad))
    with pytest.raises(ValueError, match=r"`rnd_hold`: it is where the novelty bonus's weight starts to fall"):
        check_recipe(Recipe(**bonus, rnd_hold=0.5))
    with pytest.raises(ValueError, match=r"`rnd_hold`: it is the novelty bonus's; allowed with rnd_coef > 0"):
        check_recipe(Recipe(obs_type="grayscale", network="small", rnd_hold=0.5))
    check_recipe(Recipe(**bonus, rnd_floor=0.0, rnd_hold=0.5))


def test_a_run_with_a_falling_weight_parts_from_the_constant_one_after_its_first_update(tmp_path):
    """The loop schedules the weight before each rollout: the first update (at 0 env steps) is the constant
    weight's, row for row, the later ones are not; the recipe file keeps the floor."""
    import csv

    from chopperscape.learn import train

    def rows(name, **kw):
        train.train(_recipe(rnd_coef=0.5, rnd_own_value=True, **kw), tmp_path / name)
        with open(tmp_path / name / "progress.csv", newline="") as f:
            return [{k: v for k, v in r.items() if k != "wall_s"} for r in csv.DictReader(f)]

    constant, falling = rows("constant"), rows("falling", rnd_floor=0.0)
    assert len(constant) == len(falling) == 6
    assert constant[0] == falling[0] and constant[1:] != falling[1:]
    assert json.loads((tmp_path / "falling" / "recipe.json").read_text())["rnd_floor"] == 0.0
