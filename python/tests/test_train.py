"""The PPO recipe's training loop (`chopperscape.learn.train`): a run trains, saves and evaluates; runs are
reproducible and follow env steps, not the clock; the progress diagnostics are sane; the pixel preset at a smoke size.
Smoke sizes only: learning itself is a benchmark (README, docs/learning.md)."""

from __future__ import annotations

import functools
import json
import math
from typing import Any

import numpy as np
import pytest
from conftest import needs_torch, progress_rows

from chopperscape.learn.presets import NOVELTY
from chopperscape.learn.recipe import LATER_SETTINGS


@needs_torch
def test_recipe_trains_saves_and_evaluates(tmp_path, capsys):
    from chopperscape.learn import evaluate, players, train
    from chopperscape.learn.recipe import Recipe

    recipe = Recipe(num_envs=8, num_steps=64, env_options={"max_fuel": 200}, hidden=32, total_steps=3000)
    path = train.train(recipe, tmp_path)
    rows = (tmp_path / "progress.csv").read_text().splitlines()
    assert rows[0] == ",".join(train.CSV_COLUMNS)
    last = dict(zip(train.CSV_COLUMNS, rows[-1].split(",")))
    assert int(last["env_steps"]) >= 3000 and int(last["episodes"]) > 0
    assert all(math.isfinite(float(v)) for v in last.values() if v != "")
    # The checkpoint reloads into the same policy: evaluation is reproducible and uses the training options.
    assert evaluate.main([str(path), "--episodes", "3", "--seed", "77"]) == 0
    first = json.loads(capsys.readouterr().out)
    assert evaluate.main([str(path), "--episodes", "3", "--seed", "77", "--per-episode"]) == 0
    second = json.loads(capsys.readouterr().out)
    assert {k: first[k] for k in first if k != "per_episode"} == {k: second[k] for k in first}
    assert first["episodes"] == 3 and sum(first["causes"].values()) == pytest.approx(1.0, abs=0.01)
    assert [e["seed"] for e in second["per_episode"]] == [77, 78, 79]
    # max_fuel=200 came from the model: evaluate plays under the options the model was trained with, and giving
    # them again explicitly changes nothing.
    _, options = players.load_recipe(path, False, 0, {})
    assert options["max_fuel"] == 200
    assert (
        evaluate.main([str(path), "--episodes", "3", "--seed", "77", "--per-episode", "--option", "max_fuel=200"]) == 0
    )
    assert json.loads(capsys.readouterr().out) == second


@needs_torch
def test_recipe_runs_are_reproducible_and_follow_env_steps_not_the_clock(tmp_path):
    from chopperscape.learn import train
    from chopperscape.learn.recipe import Recipe

    def run(name, **kw):
        recipe = Recipe(num_envs=8, num_steps=64, env_options={"max_fuel": 150}, hidden=16, total_steps=6000, **kw)
        train.train(recipe, tmp_path / name)
        return progress_rows(tmp_path / name / "progress.csv")

    first, second = run("a"), run("b")
    assert len(first) >= 5
    # Identical apart from the time column: same seed and budget, same curve, whatever the host's load.
    drop = [{k: v for k, v in r.items() if k != "wall_s"} for r in first]
    assert drop == [{k: v for k, v in r.items() if k != "wall_s"} for r in second]
    # The learning rate anneals linearly over the step budget from the start: lr = 3e-4 * (1 - steps / budget).
    lrs = [float(r["learning_rate"]) for r in first]
    assert lrs == sorted(lrs, reverse=True) and lrs[0] == 3e-4 and lrs[-1] < 1e-4
    steps_before = [0] + [int(r["env_steps"]) for r in first[:-1]]
    for r, before in zip(first, steps_before):
        assert float(r["learning_rate"]) == pytest.approx(3e-4 * max(1 - before / 6000, 0.05), rel=1e-4)
    # Another seed is another run.
    assert [r["mean_return"] for r in run("c", seed=1)] != [r["mean_return"] for r in first]


def test_the_learning_rate_stops_at_its_floor():
    from chopperscape.learn import ppo
    from chopperscape.learn.recipe import LR_FLOOR, Recipe

    def rates(**kw):
        r = Recipe(learning_rate=1e-3, total_steps=1000, **kw)
        return [ppo.learning_rate(r, t) for t in (0, 500, 900, 1000, 2000)]

    assert rates() == pytest.approx([1e-3, 5e-4, 1e-4, LR_FLOOR * 1e-3, LR_FLOOR * 1e-3])
    assert rates(lr_floor=0.3) == pytest.approx([1e-3, 5e-4, 3e-4, 3e-4, 3e-4])
    assert rates(lr_floor=1.0) == rates(anneal_lr=False) == [1e-3] * 5
    assert rates(lr_floor=0.0)[3:] == [0.0, 0.0]


def test_the_entropy_weight_falls_to_its_floor_over_the_schedule():
    from chopperscape.learn import ppo
    from chopperscape.learn.recipe import Recipe, check_recipe

    def weights(**kw):
        r = Recipe(ent_coef=0.02, total_steps=1000, **kw)
        return [ppo.entropy_coef(r, t) for t in (0, 500, 1000, 2000)]

    # The default floor (1) keeps the weight exactly as it was, so recipes without it train bit for bit as before.
    assert weights() == [0.02] * 4
    assert weights(ent_floor=0.25) == pytest.approx([0.02, 0.0125, 0.005, 0.005])
    assert weights(ent_floor=0.0) == pytest.approx([0.02, 0.01, 0.0, 0.0])
    for bad in (-0.1, 1.5, float("nan")):
        with pytest.raises(ValueError, match=r"ent_floor"):
            check_recipe(Recipe(ent_floor=bad))


@needs_torch
def test_the_entropy_floor_changes_the_updates_after_the_first(tmp_path):
    """The loop takes the entropy weight from the schedule: the first update (at 0 env steps) is the constant
    weight's, the later ones are not; the recipe file keeps the floor."""
    import torch

    from chopperscape.learn import train
    from chopperscape.learn.recipe import Recipe

    def run(name, **kw):
        recipe = Recipe(num_envs=8, num_steps=64, env_options={"max_fuel": 150}, hidden=16, total_steps=3072, **kw)
        train.train(recipe, tmp_path / name)
        return [{k: v for k, v in r.items() if k != "wall_s"} for r in progress_rows(tmp_path / name / "progress.csv")]

    constant, falling = run("constant"), run("falling", ent_floor=0.0)
    assert constant[0] == falling[0]
    # Later updates learn with a smaller weight, and the runs part (near the uniform policy, where the entropy's
    # gradient is small, in the weights before the printed columns).
    a = torch.load(tmp_path / "constant" / "model.pt", weights_only=True)["actor"]
    b = torch.load(tmp_path / "falling" / "model.pt", weights_only=True)["actor"]
    assert not all(torch.equal(a[k], b[k]) for k in a)
    assert json.loads((tmp_path / "falling" / "recipe.json").read_text())["ent_floor"] == 0.0


@needs_torch
def test_progress_diagnostics_are_sane(tmp_path):
    from chopperscape.learn import train
    from chopperscape.learn.recipe import Recipe

    recipe = Recipe(num_envs=8, num_steps=64, env_options={"max_fuel": 100}, hidden=16, total_steps=4000)
    train.train(recipe, tmp_path)
    rows = progress_rows(tmp_path / "progress.csv")
    for r in rows:
        # Entropy of a 5-action policy lies in [0, ln 5]; the fresh policy is nearly uniform.
        assert 0 <= float(r["entropy"]) <= math.log(5) + 1e-6
        assert 0 <= float(r["clip_frac"]) <= 1 and float(r["approx_kl"]) >= -1e-6
        assert float(r["explained_var"]) <= 1 and float(r["value_loss"]) >= 0
        if int(r["ended"]):
            assert r["mean_return"] != ""
            shares = [float(r[k]) for k in ("bird", "fuel", "limit")]
            assert sum(shares) == pytest.approx(1, abs=0.002)
    assert float(rows[0]["entropy"]) > 0.95 * math.log(5)
    # With 100 fuel and a policy that cannot yet refuel, fuel ends most episodes; no episode reaches 10,000 steps.
    ended = sum(int(r["ended"]) for r in rows)
    fuel = sum(float(r["fuel"]) * int(r["ended"]) for r in rows if int(r["ended"]))
    assert ended == int(rows[-1]["episodes"]) and fuel / ended > 0.3
    assert all(float(r["limit"] or 0) == 0 for r in rows)


@needs_torch
def test_pixel_recipe_smoke_trains_reloads_and_evaluates(tmp_path, capsys):
    import chopperscape
    from chopperscape.learn import evaluate, modelfile, networks, train

    # The pixel preset (frames alone, the 42×42 agent view) at a smoke size: few envs, few steps; the same code
    # path as the full recipe. Resuming it is test_resume's.
    out = tmp_path / "px"
    assert (
        train.main(
            [
                "--preset",
                "pixels",
                "--steps",
                "1200",
                "--num-envs",
                "8",
                "--num-steps",
                "32",
                "--out",
                str(out),
                "--option",
                "max_fuel=300",
            ]
        )
        == 0
    )
    capsys.readouterr()
    recipe = json.loads((out / "recipe.json").read_text())
    assert recipe["obs_type"] == "grayscale" and recipe["network"] == "small-coord-deep-stem"
    assert (recipe["gamma"], recipe["update_epochs"], recipe["num_minibatches"]) == (0.998, 1, 16)
    # No teacher and no auxiliary loss on privileged state: nothing but the frames trains it.
    assert (recipe["teacher"], recipe["aux_coef"], recipe["gae_lambda"]) == ("", 0.0, 0.98)
    assert recipe["env_options"] == {"obs_size": [42, 42], "frame_stack": 4, "frame_skip": 4, "max_fuel": 300}
    rows = progress_rows(out / "progress.csv")
    assert rows and all(math.isfinite(float(r[k])) for r in rows for k in ("entropy", "value_loss", "policy_loss"))
    import torch

    payload = torch.load(out / "model.pt", weights_only=True)
    assert payload["obs_shape"] == [42, 42, 4] and payload["pixels_version"] == chopperscape.PIXELS_VERSION
    # A model of a later pixel layout is refused, naming both versions; one of an older layout is shown that
    # layout (version 2: the art; version 1: the art and the text HUD), its own options over those.
    later = chopperscape.PIXELS_VERSION + 1
    with pytest.raises(ValueError, match=f"pixel layout v{later}, and this chopperscape draws v{later - 1}"):
        modelfile.agent_from_checkpoint({**payload, "pixels_version": later})
    assert modelfile.from_payload({**payload, "pixels_version": 2}).recipe["env_options"]["look"] == "art"
    old = modelfile.from_payload({**payload, "pixels_version": 1}).recipe["env_options"]
    assert (old["look"], old["hud_style"], old["max_fuel"]) == ("art", "text", 300)
    assert "look" not in modelfile.from_payload(payload).recipe["env_options"]
    agent = modelfile.agent_from_checkpoint(payload)
    assert isinstance(agent, networks.CnnAgent)
    # The frame skip, stack and size came back from the model: evaluation plays the frames it was trained on.
    assert evaluate.main([str(out / "model.pt"), "--episodes", "2", "--seed", "9", "--per-episode"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["episodes"] == 2 and all(e["return"] % 4 == 0 or e["cause"] == "bird" for e in res["per_episode"])
    # Reloading gives the same greedy actions on the same frames.
    env_obs = np.random.default_rng(0).integers(0, 256, (3, 42, 42, 4), dtype=np.uint8)
    again = modelfile.agent_from_checkpoint(torch.load(out / "model.pt", weights_only=True))
    with torch.no_grad():
        assert torch.equal(agent.actor(torch.from_numpy(env_obs)), again.actor(torch.from_numpy(env_obs)))


#: The preset's schedule from the ninth session to the thirtieth (12 M since): what a run of those sessions adds to
#: today's preset's flags.
EIGHT_M = {"total_steps": 8_000_000}
#: What a run of the preset before the twenty-fourth session adds to the preset's flags: no novelty bonus (the
#: preset's `NOVELTY` since) and the 8 M schedule. The flags below are those that give each run's recipe on today's
#: preset.
BEFORE_NOVELTY = {**{k: LATER_SETTINGS[k] for k in NOVELTY}, **EIGHT_M}
#: The earlier pixel preset (until the ninth session): the plain small CNN, 2 epochs of 4 minibatches at 1e-3 over
#: 10 M decisions (docs/learning.md gives its flags).
EARLIER_PIXELS = {
    **BEFORE_NOVELTY,
    "network": "small",
    "update_epochs": 2,
    "num_minibatches": 4,
    "learning_rate": 1e-3,
    "vf_coef": 0.5,
    "total_steps": 10_000_000,
}


#: The target's seeds trained and collected so far (docs/curves/pixels-seeds/target.csv has each one's line).
TARGET_SEEDS = (0, 1, 2, 3, 4, 100, 101, 102, 103, 104)


#: The candidate recipe's seeds run so far (docs/curves/pixels-candidates/ent02-12m/target.csv), and its flags.
CANDIDATE_SEEDS = (0, 3, 102)
CANDIDATE_ENT02_12M = {
    **BEFORE_NOVELTY,
    "torch_compile": True,
    "torch_threads": 2,
    "total_steps": 12_000_000,
    "ent_coef": 0.02,
}
#: The seventeenth session's candidate, that entropy falling to half of itself (docs/curves/pixels-candidates/
#: ent02f05-12m/target.csv), its seeds run so far and its flags.
CANDIDATE_F05_SEEDS = (0, 102)
CANDIDATE_ENT02F05_12M = {**CANDIDATE_ENT02_12M, "ent_floor": 0.5}
#: The nineteenth session's: RND with its own value head on the preset's 8 M schedule (docs/curves/pixels-candidates/
#: rndown05/target.csv; seed 102 begun in the seventeenth session and resumed, seed 0 the twentieth's and seed 2 the
#: twenty-first's, seed 103 the twenty-second's, each in one call), its seeds run so far and its flags.
CANDIDATE_RNDOWN05_SEEDS = (0, 2, 102, 103)
CANDIDATE_RNDOWN05 = {
    "torch_compile": True,
    "torch_threads": 2,
    "rnd_coef": 0.5,
    "rnd_own_value": True,
    "rnd_pool": 1,
    **EIGHT_M,
}
#: The twenty-third session's: the same bonus on frames pooled 2×2 (docs/curves/pixels-candidates/rndpool2/target.csv;
#: seed 102 the twenty-second session's probe resumed to the end, seed 2 the twenty-third's in one call, seed 0 begun
#: there and resumed in the twenty-fourth, seed 3 begun in the twenty-fourth and resumed in the twenty-fifth, seeds 1
#: and 4 the twenty-fifth's, each in one call; 100, 101, 103 and 104 the twenty-eighth's, each in one call on a Zen 5
#: EPYC). From the twenty-fourth session to the thirtieth these flags were the preset's own.
CANDIDATE_RNDPOOL2_SEEDS = (0, 1, 2, 3, 4, 100, 101, 102, 103, 104)
CANDIDATE_RNDPOOL2 = {**CANDIDATE_RNDOWN05, "rnd_pool": 2}
#: The twenty-sixth session's: the preset with the bonus's weight falling to nothing over the 8 M
#: (docs/curves/pixels-candidates/rndfloor0/target.csv; seeds 3 and 102, each in one call), its seeds and its flags.
CANDIDATE_RNDFLOOR0_SEEDS = (3, 102)
CANDIDATE_RNDFLOOR0 = {**CANDIDATE_RNDPOOL2, "rnd_floor": 0.0}
#: The twenty-sixth session's: the weight held over the first half, then falling to nothing
#: (docs/curves/pixels-candidates/rndhold05/target.csv; seed 102 begun in the twenty-sixth session and resumed in the
#: twenty-seventh, seed 3 the twenty-seventh's in one call), its seeds and its flags.
CANDIDATE_RNDHOLD05_SEEDS = (3, 102)
CANDIDATE_RNDHOLD05 = {**CANDIDATE_RNDPOOL2, "rnd_floor": 0.0, "rnd_hold": 0.5}
#: The preset on the 12 M schedule (docs/curves/pixels-candidates/rndpool2-12m/target.csv; seed 104 the
#: twenty-eighth session's probe, collected in the twenty-ninth, seeds 101, 3 and 4 the twenty-ninth's, 0, 2, 100
#: and 102 the thirtieth's, each in one call on a Zen 5 EPYC; seeds 1 and 103 in two, resumed from their checkpoints
#: in the thirtieth and thirty-first), its seeds and its flags: since the thirty-first session `--preset pixels`.
CANDIDATE_RNDPOOL2_12M_SEEDS = (0, 1, 2, 3, 4, 100, 101, 102, 103, 104)
CANDIDATE_RNDPOOL2_12M = {**CANDIDATE_RNDPOOL2, "total_steps": 12_000_000}
#: Every candidate collected apart (`collect_target.py RUNS --out docs/curves/pixels-candidates/NAME`, by the target's
#: protocol, `target43.sh SEED RUNS -- FLAGS`): its folder's NAME, its seeds run so far and its flags. Both tests
#: below read it, so a candidate's folder, seeds and recipe are named once.
CANDIDATES = (
    ("ent02-12m", CANDIDATE_SEEDS, CANDIDATE_ENT02_12M),
    ("ent02f05-12m", CANDIDATE_F05_SEEDS, CANDIDATE_ENT02F05_12M),
    ("rndown05", CANDIDATE_RNDOWN05_SEEDS, CANDIDATE_RNDOWN05),
    ("rndpool2", CANDIDATE_RNDPOOL2_SEEDS, CANDIDATE_RNDPOOL2),
    ("rndfloor0", CANDIDATE_RNDFLOOR0_SEEDS, CANDIDATE_RNDFLOOR0),
    ("rndhold05", CANDIDATE_RNDHOLD05_SEEDS, CANDIDATE_RNDHOLD05),
    ("rndpool2-12m", CANDIDATE_RNDPOOL2_12M_SEEDS, CANDIDATE_RNDPOOL2_12M),
)


@functools.cache
def _collect_target() -> Any:
    """docs/curves/pixels-probes/collect_target.py (a standard-library script), loaded once from its file."""
    import importlib.util
    import pathlib

    path = pathlib.Path(__file__).resolve().parents[2] / "docs" / "curves" / "pixels-probes" / "collect_target.py"
    spec = importlib.util.spec_from_file_location("collect_target", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _target_set(seed: int) -> str:
    """The folder of docs/curves/pixels-seeds a target seed is collected into (training seeds or never tuned on), by
    the collector's own rule (`collect_target.set_of`)."""
    return str(_collect_target().set_of(seed))


@pytest.mark.parametrize(
    "folder, seeds",
    [
        ("pixels-seeds", TARGET_SEEDS),
        *((f"pixels-candidates/{name}", seeds) for name, seeds, _ in CANDIDATES),
    ],
)
def test_the_targets_collected_seeds_are_the_ones_checked_here(folder, seeds):
    """Every seed with a line in a collection's table (the preset's, a candidate's) has its curve, recipe and
    evaluation, and its recipe is checked against the preset below (TARGET_SEEDS, CANDIDATE_SEEDS), so a seed
    collected later cannot escape that check."""
    import csv
    import pathlib

    seeds_dir = pathlib.Path(__file__).resolve().parents[2] / "docs" / "curves" / folder
    with open(seeds_dir / "target.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert tuple(sorted(int(r["seed"]) for r in rows)) == tuple(sorted(seeds))
    for r in rows:
        folder = seeds_dir / _target_set(int(r["seed"]))
        for ext in ("csv", "recipe.json", "eval.json"):
            assert (folder / f"seed-{r['seed']}.{ext}").is_file()
        evaluation = json.loads((folder / f"seed-{r['seed']}.eval.json").read_text())
        assert (evaluation["episodes"], evaluation["seed"], evaluation["greedy"]) == (100, 1_000_000, True)
        assert f"{evaluation['mean_return']:.1f}" == r["mean_return"]
        summary = json.loads((folder / "summary.json").read_text())
        assert summary["steps"] == json.loads((folder / f"seed-{r['seed']}.recipe.json").read_text())["total_steps"]


@needs_torch
def test_a_candidates_seeds_are_collected_apart_with_their_own_schedule(tmp_path, monkeypatch):
    """`collect_target.py RUNS --out FOLDER` gathers a candidate's seeds into FOLDER, not the preset's
    pixels-seeds/: each seed's files, its table line, and a summary that states the seeds' own schedule (12 M
    here, 8 M in pixels-seeds/), with the preset's baselines copied rather than played again; seeds of two
    schedules in one set are refused by name, and pixels-seeds/ is left as it was."""
    import pathlib
    import shutil
    import sys

    curves = pathlib.Path(__file__).resolve().parents[2] / "docs" / "curves"
    kept = curves / "pixels-candidates" / "ent02-12m"
    runs = tmp_path / "runs"
    for seed, source in ((102, kept / "100-104" / "seed-102"), (101, curves / "pixels-seeds" / "100-104" / "seed-101")):
        run = runs / f"seed-{seed}"
        run.mkdir(parents=True)
        decisions = progress_rows(source.with_suffix(".csv"))[-1]["env_steps"]
        shutil.copyfile(source.with_suffix(".csv"), run / "progress.csv")
        shutil.copyfile(source.with_suffix(".recipe.json"), run / "recipe.json")
        shutil.copyfile(source.with_suffix(".eval.json"), run / f"eval-{decisions}.json")
    header, *lines = (kept / "target.csv").read_text().splitlines()
    line102 = next(line for line in lines if line.startswith("102,"))
    (runs / "target.csv").write_text(f"{header}\n{','.join(line102.split(',')[:-1])}\n")
    before = (curves / "pixels-seeds" / "target.csv").read_text()
    out = tmp_path / "candidate"
    monkeypatch.setattr(sys, "argv", ["collect_target.py", str(runs), "--out", str(out), "--machine", "test"])
    assert _collect_target().main() == 0
    summary = json.loads((out / "100-104" / "summary.json").read_text())
    assert summary["steps"] == 12_000_000
    assert summary["seeds"] == [102]
    for name in ("random", "heuristic"):
        assert (out / "100-104" / f"baseline-{name}.json").read_bytes() == (
            curves / "pixels-seeds" / "100-104" / f"baseline-{name}.json"
        ).read_bytes()
    assert (out / "target.csv").read_text().splitlines()[1].endswith(",test")
    # Seed 101 of the preset as it was (8 M) joins the same set: its summary would mix two schedules.
    line101 = (curves / "pixels-seeds" / "target.csv").read_text().splitlines()
    row101 = next(r for r in line101 if r.startswith("101,"))
    with open(runs / "target.csv", "a") as f:
        f.write(",".join(row101.split(",")[:-1]) + "\n")
    with pytest.raises(ValueError, match=r"different schedules \(\[8000000, 12000000\]\)"):
        _collect_target().main()
    assert (curves / "pixels-seeds" / "target.csv").read_text() == before


@pytest.mark.parametrize(
    "seed, name, flags",
    [
        # Issue 43's target runs since the twelfth session (the preset with the speed flags; every seed collected
        # into docs/curves/pixels-seeds by collect_target.py), and the probes of the value loss at weight 1.0 that
        # made it the preset, one thread each.
        *(
            (
                s,
                f"../pixels-seeds/{_target_set(s)}/seed-{s}",
                {**BEFORE_NOVELTY, "torch_compile": True, "torch_threads": 2},
            )
            for s in TARGET_SEEDS
        ),
        *((s, f"p43-vf1-seed{s}", {**BEFORE_NOVELTY, "torch_compile": True, "torch_threads": 1}) for s in (0, 3)),
        # The fourteenth session's longer schedule, by the target's protocol (`target43.sh 102 RUNS -- --steps ...`).
        *(
            (
                s,
                f"p43-steps12m-seed{s}",
                {**BEFORE_NOVELTY, "torch_compile": True, "torch_threads": 2, "total_steps": 12_000_000},
            )
            for s in (2, 102, 103)
        ),
        # Probes on the stalled seed 102 (`probe43.sh NAME UNTIL RUNS 102 -- FLAGS`, one thread): entropy 0.02 (the
        # thirteenth and fifteenth sessions) and the exploration bonus `--rnd-coef 0.5` (the fifteenth).
        (102, "p43-ent02-seed102", {**BEFORE_NOVELTY, "torch_compile": True, "torch_threads": 1, "ent_coef": 0.02}),
        (102, "p43-rnd05-seed102", {**BEFORE_NOVELTY, "torch_compile": True, "torch_threads": 1, "rnd_coef": 0.5}),
        # The seventeenth session's RND with its own value head (to 2.39 M of 8 M, alone on both cores).
        (102, "p43-rndown05-seed102", CANDIDATE_RNDOWN05),
        # RND with its own value at a quarter share: the eighteenth session's 18 minutes, then the twentieth's run by
        # the target's protocol (the same first 2.08 M row for row), stopped at 4.07 M of 8 M; alone on both cores.
        (102, "p43-rndown25-seed102", {**CANDIDATE_RNDOWN05, "rnd_proportion": 0.25}),
        # The preset's never-tuned seed 100 by the target's protocol on the Zen 3 EPYC, cut by the twenty-seventh
        # session's end; its checkpoint was lost with that machine, and the twenty-eighth session's run of the seed
        # (another CPU: its float rounding parts from the first update on) is the collected one.
        (100, "p43-rndpool2-seed100", CANDIDATE_RNDPOOL2),
        # The twenty-third session's bonus on frames pooled 4×4 (to 2.39 M of 8 M, alone on both cores).
        (102, "p43-rndpool4-seed102", {**CANDIDATE_RNDOWN05, "rnd_pool": 4}),
        # The eighteenth session's preset on seed 102 on the Zen 3 machine (`target43.sh 102 RUNS 45`, cut at 6.33 M).
        (102, "p43-zen3-seed102", {**BEFORE_NOVELTY, "torch_compile": True, "torch_threads": 2}),
        # The candidates' seeds by the target's protocol, each collected apart (CANDIDATES).
        *(
            (s, f"../pixels-candidates/{name}/{_target_set(s)}/seed-{s}", flags)
            for name, seeds, flags in CANDIDATES
            for s in seeds
        ),
        # The ninth to eleventh sessions' target runs, of the preset before its value loss doubled.
        *(
            (
                s,
                f"p43-target-stem8m-seed{s}",
                {**BEFORE_NOVELTY, "torch_compile": True, "torch_threads": 2, "vf_coef": 0.5},
            )
            for s in range(5)
        ),
        # The earlier preset's runs (issue 28's three seeds), with the flags that give its learning settings back.
        (0, "tf42-p3-e2-lr1e-3", EARLIER_PIXELS),
        (1, "tf42-p3-seed1", EARLIER_PIXELS),
        (2, "tf42-p3-seed2", EARLIER_PIXELS),
    ],
)
def test_the_pixel_preset_is_the_recipe_the_targets_ran(seed, name, flags):
    """README's pixel figures are of runs started with the candidate's settings as flags: issue 43's target
    (`docs/curves/pixels-probes/target43.sh`: `--preset pixels` with the speed settings `--torch-compile
    --torch-threads 2`) and, before it, issue 28's. Their committed recipes are the preset with that seed and
    those flags, field for field, so the commands the docs give reproduce them."""
    import dataclasses
    import pathlib

    from chopperscape.learn.recipe import LATER_SETTINGS, PRESETS, Recipe

    curves = pathlib.Path(__file__).resolve().parents[2] / "docs" / "curves" / "pixels-probes"
    # Settings added since (torch_compile) at the value those runs had.
    ran = {**LATER_SETTINGS, **json.loads((curves / f"{name}.recipe.json").read_text())}
    preset = dataclasses.asdict(Recipe(**{**PRESETS["pixels"], **flags}, seed=seed))
    assert ran == preset
    assert (ran["teacher"], ran["aux_coef"], ran["recon_coef"]) == ("", 0.0, 0.0)


def test_the_pixel_preset_is_the_pooled_novelty_candidate_on_12m():
    """Since the thirty-first session `--preset pixels` is the candidate its target seeds ran as flags (RND 0.5 with
    its own value head on frames pooled 2×2, over 12 M decisions): those flags add nothing to the preset but the speed
    settings, so the seeds run with them and those run with the preset alone have one recipe. The same bonus on 8 M
    (the preset from the twenty-fourth session to the thirtieth) differs from it in the schedule alone."""
    import dataclasses

    from chopperscape.learn.recipe import PRESETS, Recipe

    speed = {"torch_compile": True, "torch_threads": 2}
    twelve = dataclasses.asdict(Recipe(**{**PRESETS["pixels"], **speed}))
    assert dataclasses.asdict(Recipe(**{**PRESETS["pixels"], **CANDIDATE_RNDPOOL2_12M})) == twelve
    assert PRESETS["pixels"]["total_steps"] == 12_000_000
    eight = dataclasses.asdict(Recipe(**{**PRESETS["pixels"], **CANDIDATE_RNDPOOL2}))
    assert {k for k in eight if eight[k] != twelve[k]} == {"total_steps"}
    assert {k: PRESETS["pixels"][k] for k in NOVELTY} == {"rnd_coef": 0.5, "rnd_own_value": True, "rnd_pool": 2}
    # The GPU preset keeps what it was measured with: no bonus.
    assert Recipe(**PRESETS["pixels-large"]).rnd_coef == 0.0


GPU_FLAGS = {"device": "cuda", "torch_compile": True, "env_threads": 12, "torch_threads": 4}


@pytest.mark.parametrize(
    "seed, name, flags",
    [
        # Issue 43's GPU runs (`docs/curves/pixels-probes/gpu_large.sh`, an H200 with 16 cores): the fourteenth
        # session's on the preset's 28 M schedule, and the twelfth session's on the 8 M one it had then.
        *((s, f"gpu43-large28m-seed{s}", GPU_FLAGS) for s in (0, 1)),
        (0, "gpu43-large", {**GPU_FLAGS, "total_steps": 8_000_000}),
    ],
)
def test_the_large_pixel_preset_is_the_recipe_the_gpu_runs_ran(seed, name, flags):
    """The GPU figures in docs/learning.md are of `--preset pixels-large --device cuda` with the speed flags: their
    committed recipes are the preset with that seed and those flags, field for field."""
    import dataclasses
    import pathlib

    from chopperscape.learn.recipe import LATER_SETTINGS, PRESETS, Recipe

    curves = pathlib.Path(__file__).resolve().parents[2] / "docs" / "curves" / "pixels-probes"
    ran = {**LATER_SETTINGS, **json.loads((curves / f"{name}.recipe.json").read_text())}
    assert ran == dataclasses.asdict(Recipe(**{**PRESETS["pixels-large"], **flags}, seed=seed))


@needs_torch
def test_until_stops_a_run_on_the_whole_runs_schedule(tmp_path, capsys):
    from chopperscape.learn import train
    from chopperscape.learn.recipe import Recipe

    recipe = Recipe(num_envs=4, num_steps=16, hidden=8, num_minibatches=2, total_steps=4 * 16 * 6)
    train.train(recipe, tmp_path / "whole")
    train.train(recipe, tmp_path / "part", until=4 * 16 * 2 + 1)
    whole = progress_rows(tmp_path / "whole" / "progress.csv")
    part = progress_rows(tmp_path / "part" / "progress.csv")
    # The prefix of the whole run, the learning rate annealed over the whole budget, stopped at the first update
    # that reaches `until`.
    drop = [{k: v for k, v in r.items() if k != "wall_s"} for r in whole]
    assert [{k: v for k, v in r.items() if k != "wall_s"} for r in part] == drop[: len(part)]
    assert len(part) == 3 and len(whole) >= 6
    with pytest.raises(SystemExit) as e:
        train.main(["--out", str(tmp_path / "bad"), "--until", "0"])
    assert e.value.code == 2 and "until" in capsys.readouterr().err
