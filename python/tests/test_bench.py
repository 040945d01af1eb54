"""ChopperScape-Bench: the modes (one table, every surface), the protocol's seeds, reproducible results files,
the statistics against hand-computed values, and refused results files."""

from __future__ import annotations

import json
import os
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import chopperscape
import chopperscape.modes
from chopperscape import _core
from chopperscape.bench import evaluate, protocol, report, results
from chopperscape.bench.__main__ import main
from chopperscape.learn import recipe as recipe_mod
from chopperscape.learn import seeds as learn_seeds
from chopperscape.learn import stats as learn_stats

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "docs" / "bench" / "results"
MODEL = ROOT / "models" / "ppo-features.pt"


# --- modes ------------------------------------------------------------------------------------------------------


def test_modes_are_the_cores_table_and_each_has_a_gymnasium_id():
    assert [m["name"] for m in chopperscape.MODES] == ["v0", "sticky-v0", "full-v0"]
    assert chopperscape.MODES == _core.MODES
    for m in chopperscape.MODES:
        assert m["id"] in gym.registry
        if m["name"] != "v0":
            assert gym.spec(m["id"]).kwargs == {"mode": m["name"]}
    assert gym.spec("ChopperScape-v0").kwargs == {}  # v0 keeps every option open, as before


def _first_reward(env, **kw) -> float:
    env.reset(seed=0)
    return float(env.step(4, **kw)[1])


@pytest.mark.parametrize("name", ["v0", "sticky-v0", "full-v0"])
def test_mode_gives_the_same_rules_on_every_surface(name):
    m = chopperscape.modes.mode(name)
    skip = int(m["options"].get("frame_skip", "1"))
    env = chopperscape.ChopperScapeEnv(mode=name, obs_type="features")
    made = gym.make(m["id"], obs_type="features")
    envs = chopperscape.VectorEnv(2, mode=name, obs_type="features")
    vec = gym.make_vec(m["id"], num_envs=2, vectorization_mode="vector_entry_point", obs_type="features")
    for e in (env, made):
        e.reset(seed=0)
        assert e.step(4)[1] == skip  # +1 per underlying step
    for v in (envs, vec):
        v.reset(seed=0)
        assert list(v.step(np.array([4, 4]))[1]) == [skip, skip]
    # The same game: a mode equals its options given one by one.
    explicit = chopperscape.ChopperScapeEnv(obs_type="features", **protocol.mode_options(name))
    plain = {k: v for k, v in protocol.mode_options(name).items() if k != "mode"}
    by_hand = chopperscape.ChopperScapeEnv(obs_type="features", **plain)
    for e in (env, explicit, by_hand):
        e.reset(seed=5)
    for _ in range(300):
        a = [e.step(1)[:4] for e in (env, explicit, by_hand)]
        assert all(np.array_equal(a[0][0], x[0]) and a[0][1:] == x[1:] for x in a[1:])
        if a[0][2]:
            break


def test_options_that_contradict_a_mode_are_refused_and_observation_options_are_free():
    with pytest.raises(ValueError, match=r'mode "full-v0".*lives 2 != 3'):
        gym.make("ChopperScape-Full-v0", lives=2)
    with pytest.raises(ValueError, match=r"frame_skip 1 != 4"):
        chopperscape.VectorEnv(2, mode="sticky-v0", frame_skip=1)
    with pytest.raises(ValueError, match=r"bird_prob 0.02 != 0.01"):
        chopperscape.ChopperScapeEnv(mode="v0", bird_prob=0.02)
    with pytest.raises(ValueError, match="allowed None or one of v0, sticky-v0, full-v0"):
        chopperscape.ChopperScapeEnv(mode="v9")
    chopperscape.ChopperScapeEnv(mode="sticky-v0", frame_skip=4, obs_type="grayscale", obs_size=(84, 84))
    gym.make("ChopperScape-v0", lives=3)  # the plain id stays as it was


# --- protocol ---------------------------------------------------------------------------------------------------


def test_protocol_is_the_held_out_evaluation():
    assert protocol.eval_seeds() == range(1_000_000, 1_000_100)
    assert (learn_seeds.EVAL_SEED, learn_seeds.EVAL_EPISODES) == (protocol.EVAL_SEED, protocol.EVAL_EPISODES)
    assert gym.spec("ChopperScape-v0").max_episode_steps == protocol.MAX_EPISODE_STEPS


def test_training_seeds_never_reach_the_evaluation_seeds():
    # The training tools' seeds: `seed + i` for each of num_envs envs, for every preset and the default recipe.
    for preset in [None, *recipe_mod.PRESETS]:
        r = recipe_mod.Recipe() if preset is None else recipe_mod.Recipe(**recipe_mod.PRESETS[preset])
        for seed in range(10):  # `--seeds 0-9`
            protocol.check_training_seeds(r.seed + seed, r.num_envs)
    protocol.check_training_seeds(0, 1_000_000)
    protocol.check_training_seeds(1_000_100, 64)
    for first, count in [(1_000_000, 1), (999_990, 64), (1_000_099, 1), (0, 2_000_000)]:
        with pytest.raises(ValueError, match=r"overlap the evaluation seeds 1000000\.\.1000099"):
            protocol.check_training_seeds(first, count)


def test_declared_training_seeds_are_checked_and_recorded(capsys):
    doc = evaluate.run("chopperscape.bench.examples:always_up", "v0", train_seeds=(0, 64))
    assert doc["policy"]["train_seeds"] == [0, 64]
    args = ["evaluate", "chopperscape.bench.examples:always_up", "--mode", "v0", "--train-seeds", "999999:2"]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "overlap the evaluation seeds" in err[0]


def test_a_model_trained_on_the_evaluation_seeds_is_refused(tmp_path):
    torch = pytest.importorskip("torch")
    payload = torch.load(MODEL, weights_only=True)
    payload["recipe"]["seed"] = 999_990
    bad = tmp_path / "leaky.pt"
    torch.save(payload, bad)
    with pytest.raises(ValueError, match=r"its training seeds 999990\.\.1000053 overlap"):
        evaluate.load(str(bad), "v0")


# --- results files ----------------------------------------------------------------------------------------------


def test_the_same_policy_gives_the_same_results_twice(tmp_path, capsys):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    for out in (a, b):
        assert main(["evaluate", "random", "--mode", "sticky-v0", "--policy-seed", "3", "--out", str(out)]) == 0
    da, db = results.load(a), results.load(b)
    assert results.comparable(da) == results.comparable(db)
    assert "created" in da["meta"]
    other = evaluate.run("random", "sticky-v0", policy_seed=4)
    assert other["episodes"] != da["episodes"]  # a policy seed is a run
    assert [e["seed"] for e in da["episodes"]] == list(protocol.eval_seeds())
    assert not list(tmp_path.glob(".*tmp"))


def test_runs_named_alike_are_one_row_and_a_bad_name_is_refused(tmp_path, capsys):
    """`--name` groups the runs of one recipe (its training seeds) into one row, whatever their files' paths; a
    name the table cannot show is refused before anything is played or written."""
    paths = []
    for r in (0, 1):
        paths.append(tmp_path / f"r{r}.json")
        args = ["evaluate", "random", "--mode", "v0", "--policy-seed", str(r), "--name", "uniform", "--out"]
        assert main([*args, str(paths[-1])]) == 0
    assert results.load(paths[0])["policy"]["name"] == "uniform"
    rows = report.report([results.load(p) for p in paths], resamples=100, partial=True)
    assert [(r["policy"], r["runs"]) for r in rows] == [("uniform @ v0", {"v0": 2})]
    capsys.readouterr()
    for bad in ("", "   ", "a|b", "x" * 81, "tab\there"):
        out = tmp_path / "bad.json"
        assert main(["evaluate", "random", "--mode", "v0", "--name", bad, "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert "`policy.name`" in err and "1 to 80 printable characters" in err, err
        assert not out.exists()


def test_a_committed_row_reproduces():
    doc = results.load(RESULTS / "full-v0.random.seed7.json")
    again = evaluate.run("random", "full-v0", policy_seed=7)
    assert results.comparable(again) == results.comparable(doc)


def test_callable_and_onnx_policies(tmp_path):
    doc = evaluate.run("chopperscape.bench.examples:always_up", "v0")
    assert doc["policy"]["kind"] == "callable" and len(doc["policy"]["sha256"]) == 64
    pytest.importorskip("onnxruntime")
    onnx = evaluate.run(str(ROOT / "models" / "ppo-features.onnx"), "v0")
    pt = evaluate.run(str(MODEL), "v0")
    assert onnx["policy"]["kind"] == "onnx" and pt["policy"]["kind"] == "recipe"
    assert onnx["episodes"] == pt["episodes"]  # the export acts as the model


def test_an_onnx_policys_training_seeds_are_checked(tmp_path):
    onnx = pytest.importorskip("onnx")
    pytest.importorskip("onnxruntime")

    def exported(seeds: str | None, name: str) -> str:
        graph = onnx.load(str(ROOT / "models" / "ppo-features.onnx"))
        props = {p.key: p.value for p in graph.metadata_props if p.key != "train_seeds"}
        if seeds is not None:
            props["train_seeds"] = seeds
        del graph.metadata_props[:]
        for key, value in props.items():
            graph.metadata_props.add(key=key, value=value)
        onnx.save(graph, str(tmp_path / name))
        return str(tmp_path / name)

    # A file of 0.1.0 says nothing of its seeds; one range is recorded; several (RLlib's runners) stay in the recipe.
    assert evaluate.load(exported(None, "old.onnx"), "v0").info["train_seeds"] is None
    assert evaluate.load(exported("[[0, 64]]", "one.onnx"), "v0").info["train_seeds"] == [0, 64]
    runners = evaluate.load(exported("[[1048576, 16], [2097152, 16]]", "runners.onnx"), "sticky-v0").info
    assert runners["train_seeds"] is None
    assert json.loads(runners["recipe"]["train_seeds"]) == [[1048576, 16], [2097152, 16]]
    for seeds, message in [
        ("[[0, 64], [999990, 16]]", "its training seeds 999990..1000005 overlap the evaluation seeds"),
        ("[[0, 0]]", "count 0 must be >= 1"),
        ("{}", "train_seeds metadata must be JSON [[first, count], ...]"),
        ("[[0]]", "train_seeds metadata must be JSON [[first, count], ...]"),
        ("[[0, true]]", "train_seeds metadata must be JSON [[first, count], ...]"),
        ("[[0, 1.5]]", "train_seeds metadata must be JSON [[first, count], ...]"),
        ("seeds", "train_seeds metadata must be JSON [[first, count], ...]"),
    ]:
        path = exported(seeds, "bad.onnx")
        with pytest.raises(ValueError) as err:
            evaluate.load(path, "v0")
        assert message in str(err.value) and path in str(err.value), (seeds, str(err.value))


def test_an_sb3_zip_plays_the_mode_it_is_given(tmp_path):
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO

    from chopperscape.integrations.sb3 import ChopperScapeVecEnv

    venv = ChopperScapeVecEnv(4, seed=0, mode="sticky-v0", obs_type="features")
    model = PPO("MlpPolicy", venv, n_steps=16, batch_size=32, n_epochs=1, seed=0, device="cpu")
    model.learn(64)
    model.save(tmp_path / "tiny.zip")
    doc = evaluate.run(str(tmp_path / "tiny.zip"), "sticky-v0", {"obs_type": "features"}, train_seeds=(0, 4))
    assert doc["policy"]["kind"] == "sb3" and doc["policy"]["actions"] == "greedy"
    assert doc["mode"]["name"] == "sticky-v0" and doc["policy"]["train_seeds"] == [0, 4]
    again = evaluate.run(str(tmp_path / "tiny.zip"), "sticky-v0", {"obs_type": "features"}, train_seeds=(0, 4))
    assert results.comparable(again) == results.comparable(doc)


def test_atomic_write_leaves_the_old_file_on_failure(tmp_path, monkeypatch):
    target = tmp_path / "r.json"
    target.write_text("old")

    def fail(*_):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", fail)
    with pytest.raises(OSError):
        results.write_atomic(target, "new")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["r.json"]


def _good() -> dict:
    return json.loads((RESULTS / "v0.random.seed0.json").read_text())


@pytest.mark.parametrize(
    "damage, says",
    [
        (lambda d: "{not json", "not JSON"),
        (lambda d: json.dumps(d)[:500], "not JSON"),
        (lambda d: json.dumps({**d, "format": "x"}), "`format`"),
        (lambda d: json.dumps({**d, "episodes": d["episodes"][:99]}), "`episodes` must hold 100"),
        (lambda d: json.dumps({**d, "summary": {**d["summary"], "mean_return": 1e6}}), "`summary` does not match"),
        (lambda d: json.dumps({**d, "protocol": {**d["protocol"], "episodes": 10}}), "`protocol`"),
        (lambda d: json.dumps({**d, "mode": {**d["mode"], "name": "v7"}}), "unknown mode"),
        (lambda d: json.dumps({**d, "policy": {**d["policy"], "train_seeds": [1_000_000, 4]}}), "overlap"),
        (lambda d: json.dumps({**d, "policy": {**d["policy"], "name": "a | b"}}), "`policy.name`"),
        (lambda d: json.dumps({**d, "policy": {**d["policy"], "name": 3}}), "`policy.name`"),
    ],
)
def test_a_malformed_results_file_is_refused_with_its_name(tmp_path, damage, says):
    bad = tmp_path / "bad.json"
    bad.write_text(damage(_good()))
    cmd = [sys.executable, "-m", "chopperscape.bench", "report", str(RESULTS / "v0.heuristic.json"), str(bad)]
    done = subprocess.run(cmd, capture_output=True, text=True)
    assert done.returncode == 2
    assert done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and str(bad) in lines[0] and says in lines[0], done.stderr


# --- statistics -------------------------------------------------------------------------------------------------

#: Two tasks of four runs: hand-computed below.
TASKS = [np.array([0.1, 0.2, 0.3, 1.4]), np.array([0.5, 0.6, 0.9, 1.0])]


def test_aggregates_match_hand_computed_values_and_rliables_definitions():
    # mean of per-task means: (0.5 + 0.75) / 2; median of two per-task means = their mean too.
    assert report.aggregate_mean(TASKS) == pytest.approx(0.625)
    assert report.aggregate_median(TASKS) == pytest.approx(0.625)
    # IQM pools 8 runs, drops the lowest 2 (0.1, 0.2) and the highest 2 (1.0, 1.4): mean(0.3, 0.5, 0.6, 0.9).
    assert report.aggregate_iqm(TASKS) == pytest.approx(0.575)
    # Optimality gap at 1: 1 - mean(min(x, 1)) = 1 - (0.1+0.2+0.3+1+0.5+0.6+0.9+1)/8.
    assert report.aggregate_optimality_gap(TASKS) == pytest.approx(1 - 4.6 / 8)
    # rliable.metrics, written out on the (runs x tasks) matrix.
    m = np.stack(TASKS, axis=1)
    assert report.aggregate_mean(TASKS) == pytest.approx(np.mean(np.mean(m, axis=0)))
    assert report.aggregate_median(TASKS) == pytest.approx(np.median(np.mean(m, axis=0)))
    pooled = np.sort(m, axis=None)  # scipy.stats.trim_mean(m, 0.25, axis=None): cut int(0.25 n) from each end
    cut = int(0.25 * pooled.size)
    assert report.aggregate_iqm(TASKS) == pytest.approx(pooled[cut : pooled.size - cut].mean())
    three = TASKS + [np.array([0.0, 0.0, 0.1, 0.1])]
    assert report.aggregate_median(three) == pytest.approx(0.5)  # the median of 0.5, 0.75, 0.05
    # The performance profile: fraction of runs above tau, averaged over tasks.
    prof = report.performance_profile(TASKS, np.array([0.0, 0.25, 0.95, 2.0]))
    assert prof.tolist() == pytest.approx([1.0, (0.5 + 1.0) / 2, (0.25 + 0.25) / 2, 0.0])


def test_bootstrap_intervals():
    est = report.interval_estimates(TASKS, resamples=5000)
    for name, a in est.items():
        assert a["low"] <= a["point"] <= a["high"], name
    # Constant runs: no spread at all.
    flat = report.interval_estimates([np.full(5, 0.4)], resamples=500)
    assert all(a["low"] == a["high"] == pytest.approx(a["point"]) for a in flat.values())
    # With one task the stratified bootstrap is the plain one over runs (learn.stats.bootstrap_ci, same draws).
    x = np.array([0.1, 0.5, 0.2, 0.9, 0.4, 0.45, 0.3, 0.8, 0.7, 0.05])
    lo, hi = learn_stats.bootstrap_ci(x, resamples=4000, seed=0)
    one = report.interval_estimates([x], resamples=4000, seed=0)["iqm"]
    assert (one["low"], one["high"]) == pytest.approx((lo, hi))
    # Reproducible: a seeded generator.
    assert report.interval_estimates(TASKS, resamples=800) == report.interval_estimates(TASKS, resamples=800)


def test_report_over_the_committed_results_and_its_plots(tmp_path):
    files = sorted(str(p) for p in RESULTS.glob("*.json"))
    assert len(files) >= 34
    assert main(["report", *files, "--plots", str(tmp_path), "--format", "svg", "--resamples", "500"]) == 0
    assert (tmp_path / "intervals.svg").stat().st_size > 0 and (tmp_path / "profile.svg").stat().st_size > 0
    rows = report.report(report.load_all(files), resamples=500)
    runs = {r["policy"]: r["runs"] for r in rows}
    for m in ("v0", "sticky-v0", "full-v0"):
        assert runs[f"random @ {m}"] == {m: 10}
        assert runs[f"heuristic @ {m}"] == {m: 1}


def test_the_leaderboard_page_shows_the_committed_results():
    page = (ROOT / "docs" / "site" / "bench.md").read_text()
    files = sorted(str(p) for p in RESULTS.glob("*.json"))
    for row in report.markdown(report.report(report.load_all(files))).splitlines()[2:]:
        assert row in page, f"docs/site/bench.md lacks the row (regenerate it, see the page):\n{row}"


#: The trained rows (chopperscape.bench.rows), and the command that trains each (after the interpreter).
TRAINED_ROWS = {
    "fast": ["-m", "chopperscape.learn.train", "--preset", "fast"],
    "features": ["-m", "chopperscape.learn.train", "--mode"],
    "sb3-ppo": ["-m", "chopperscape.integrations.sb3_train", "ppo"],
    "sb3-dqn": ["-m", "chopperscape.integrations.sb3_train", "dqn"],
    "rllib-ppo": ["-m", "chopperscape.integrations.rllib.ppo"],
    # The pixel preset at its stated budget, with the target protocol's speed flags (compiled, two threads).
    "pixels": ["-m", "chopperscape.learn.train", "--preset", "pixels", "--torch-compile", "--torch-threads", "2"],
    # The preset until the ninth session, which the first pixel rows ran (today's preset with these flags).
    "pixels-p3": ["-m", "chopperscape.learn.train", "--preset", "pixels", "--network", "small", "--update-epochs", "2"],
}


def _row(*args: str, results: Path, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    """`python -m chopperscape.bench row ARGS --results RESULTS --python py` in a subprocess."""
    command = [sys.executable, "-m", "chopperscape.bench", "row", *args, "--results", str(results), "--python", "py"]
    return subprocess.run(command + ["--rllib-python", "rpy"], capture_output=True, text=True, cwd=cwd, timeout=300)


def _commands(done: subprocess.CompletedProcess[str]) -> list[list[str]]:
    assert done.returncode == 0, done.stderr
    return [shlex.split(line) for line in done.stdout.splitlines() if not line.endswith("skipped")]


def test_the_rows_are_the_committed_rows():
    """Every trained row of the leaderboard is declared in the package, under the name its committed files carry."""
    from chopperscape.bench import rows

    assert set(rows.ROWS) == set(TRAINED_ROWS)
    for f in [*RESULTS.glob("*.seed*.json"), *(ROOT / "docs" / "bench" / "in-progress").glob("*.json")]:
        mode, key, _ = f.name.split(".", 2)
        if key in rows.ROWS:
            assert json.loads(f.read_text())["policy"]["name"] == rows.ROWS[key].name(), f.name
            assert mode in rows.ROWS[key].modes


@pytest.mark.parametrize("row", sorted(TRAINED_ROWS))
@pytest.mark.parametrize("mode", ["sticky-v0", "full-v0"])
def test_bench_row_trains_each_seed_on_the_mode_and_evaluates_it_under_the_rows_name(row, mode, tmp_path):
    """`bench row --dry-run` prints its commands: each seed is trained on the mode's rules with that seed, then its
    model evaluated on the same mode under the row's name with its training record, into MODE.ROW.seedS.json."""
    from chopperscape.bench import rows

    commands = _commands(_row(row, "--mode", mode, "--seeds", "3,7", "--runs", "runs", "--dry-run", results=tmp_path))
    evaluations = [c for c in commands if c[1:4] == ["-m", "chopperscape.bench", "evaluate"]]
    assert len(evaluations) == 2 and len(commands) == 4
    for seed, ev in zip((3, 7), evaluations):
        train = commands[commands.index(ev) - 1]
        assert train[0] == ("rpy" if row == "rllib-ppo" else "py") and ev[0] == "py"
        assert train[1 : 1 + len(TRAINED_ROWS[row])] == TRAINED_ROWS[row]
        flags = " ".join(train)
        assert f"--seed {seed} " in flags or f"--seed={seed} " in flags
        assert f"--mode {mode}" in flags or f'"mode": "{mode}"' in flags  # or RLlib's env config
        assert ev[ev.index("--mode") + 1] == mode
        assert ev[ev.index("--out") + 1] == str(tmp_path / f"{mode}.{row}.seed{seed}.json")
        assert ev[ev.index("--training") + 1] == f"runs/seed-{seed}/training.json"
        assert ev[4] == f"runs/seed-{seed}/{rows.ROWS[row].model}"
        assert results.check_name(ev[ev.index("--name") + 1]) == rows.ROWS[row].name()


@pytest.mark.parametrize("mode", ["sticky-v0", "full-v0"])
def test_the_earlier_pixel_rows_command_gives_back_the_recipe_their_files_hold(mode, tmp_path):
    """The first pixel rows were trained as `--preset pixels` before the preset changed (ninth and twenty-fourth
    sessions); row `pixels-p3` keeps them, and its training command, parsed as `train` parses it, is the recipe
    each committed file records, field for field."""
    import dataclasses

    from chopperscape.bench import rows
    from chopperscape.learn import flags
    from chopperscape.learn.recipe import LATER_SETTINGS

    row = rows.ROWS["pixels-p3"]
    for seed in range(10):
        command = rows.train_command(row, mode, seed, row.steps, tmp_path / "run", "py", "rpy")
        _, recipe = flags.parse(command[3:])
        held = json.loads((RESULTS / f"{mode}.pixels-p3.seed{seed}.json").read_text())["policy"]["recipe"]
        assert dataclasses.asdict(recipe) == {**LATER_SETTINGS, **held}, f"{mode} seed {seed}"


def test_bench_row_skips_finished_seeds_and_refuses_bad_input_in_one_line(tmp_path):
    (tmp_path / "sticky-v0.fast.seed1.json").write_text("{}")
    done = _row("fast", "--mode", "sticky-v0", "--seeds", "1-2", "--runs", "runs", "--dry-run", results=tmp_path)
    assert f"{tmp_path}/sticky-v0.fast.seed1.json exists: seed 1 skipped" in done.stdout
    assert [c[c.index("--seed") + 1] for c in _commands(done) if "--seed" in c] == ["2"]
    refused = [
        (
            ["ppo", "--mode", "sticky-v0"],
            "unknown row 'ppo': allowed fast, features, sb3-ppo, sb3-dqn, rllib-ppo, pixels, pixels-p3",
        ),
        (["fast", "--mode", "v0"], "--mode 'v0' is not a mode of row fast: allowed sticky-v0, full-v0"),
        (["fast", "--mode", "full-v0", "--seeds", "*"], "--seeds '*': allowed numbers and ranges such as 0-9 or 0,3,5"),
        (["fast", "--mode", "full-v0", "--seeds", "0-9,x"], "--seeds '0-9,x': allowed numbers and ranges"),
        (["fast", "--mode", "full-v0", "--seeds", "5-2"], "--seeds '5-2': '5-2' is out of bounds; allowed numbers"),
        (["fast", "--mode", "full-v0", "--steps", "3e6"], "--steps '3e6': allowed a whole number of decisions from 1"),
    ]
    for args, says in refused:
        done = _row(*args, "--runs", str(tmp_path / "runs"), results=tmp_path)
        assert (done.returncode, done.stdout) == (2, "") and done.stderr.startswith(f"error: {says}")
        assert done.stderr.count("\n") == 1, done.stderr
    assert not (tmp_path / "runs").exists()
    # --steps sets the budget and the row's name with it.
    train, ev = _commands(_row("sb3-dqn", "--mode", "full-v0", "--seeds", "0", "--runs", "r", "--steps", "250000",
                               "--dry-run", results=tmp_path))  # fmt: skip
    assert train[train.index("--steps") + 1] == "250000"
    assert ev[ev.index("--name") + 1] == "SB3 DQN, stock, 250 k decisions"


def test_seeds_are_numbers_and_ranges():
    from chopperscape.bench.rows import budget, parse_seeds

    assert parse_seeds("0-9") == list(range(10)) and parse_seeds("7,0-2,2") == [0, 1, 2, 7]
    for bad in ("", "1,", "-1", "1-", "a", "0-9 ", "1..3", "0-1000000", "0-5000"):
        with pytest.raises(ValueError, match="allowed numbers and ranges"):
            parse_seeds(bad)
    assert (budget(3_000_000), budget(250_000), budget(2048)) == ("3 M", "250 k", "2,048")


def test_bench_row_leaves_a_seed_another_process_holds(tmp_path):
    """Several `bench row` on one row share its seeds: a seed whose lock another process holds is skipped, and
    the lock is an advisory one (free again once its holder closes it; a stopped run leaves none held)."""
    import fcntl

    runs = tmp_path / "runs"
    runs.mkdir()
    (tmp_path / "sticky-v0.fast.seed2.json").write_text("{}")
    with open(runs / "seed-1.lock", "w") as held:
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        done = _row("fast", "--mode", "sticky-v0", "--seeds", "1,2", "--runs", str(runs), results=tmp_path)
    assert done.returncode == 0, done.stderr
    assert (
        done.stdout.splitlines()[0]
        == f"seed 1 is being trained by another process (its lock {runs}/seed-1.lock): skipped"
    )
    with open(runs / "seed-1.lock") as again:
        fcntl.flock(again, fcntl.LOCK_EX | fcntl.LOCK_NB)  # free


def test_bench_row_trains_evaluates_and_records_at_a_smoke_budget(tmp_path):
    """The fast row for one update: trained, its training record written, evaluated by the protocol into a results
    file that records the commit, the command, the recipe and the training seeds; run again, it is skipped, and
    with its results gone the trained seed is evaluated again without training."""
    from chopperscape.bench import record

    runs, out = tmp_path / "runs", tmp_path / "results" / "new"  # a results folder that does not exist yet is made
    args = ["fast", "--mode", "sticky-v0", "--seeds", "4", "--runs", str(runs), "--steps", "16384"]
    command = [sys.executable, "-m", "chopperscape.bench", "row", *args, "--results", str(out)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr
    doc = results.load(out / "sticky-v0.fast.seed4.json")
    t = doc["training"]
    assert doc["policy"]["name"] == "fast preset: PPO on features, 16,384 decisions"
    assert t["row"] == "fast" and t["seed"] == 4 and t["train_seeds"] == [[4, 128]] == [doc["policy"]["train_seeds"]]
    assert t["command"][1:] == ["-m", "chopperscape.learn.train", "--preset", "fast", "--mode", "sticky-v0"] + [
        "--steps", "16384", "--seed", "4", "--out", str(runs / "seed-4"), "--force"]  # fmt: skip
    assert t["settings"] == doc["policy"]["recipe"] and t["settings"]["num_envs"] == 128
    assert t["commit"] == doc["meta"]["commit"] == record.project_commit()[0]
    assert doc["meta"]["command"][3:5] == ["evaluate", str(runs / "seed-4" / "model.pt")]
    again = subprocess.run(command, capture_output=True, text=True, timeout=900)
    assert again.stdout == f"{out}/sticky-v0.fast.seed4.json exists: seed 4 skipped\n"
    log = (runs / "seed-4.log").stat().st_mtime_ns
    (out / "sticky-v0.fast.seed4.json").unlink()
    assert subprocess.run(command, capture_output=True, text=True, timeout=900).returncode == 0
    assert (runs / "seed-4.log").stat().st_mtime_ns == log  # not trained again
    assert results.load(out / "sticky-v0.fast.seed4.json")["training"] == t


def test_results_files_record_how_they_were_made_and_old_ones_still_load(tmp_path):
    """`meta.commit`, `meta.command` and `training` (chopperscape.bench.record) are optional: a file without
    them loads; with them, each is checked."""
    from chopperscape.bench import record

    doc = evaluate.run("heuristic", "v0")
    assert doc["meta"]["commit"] == record.project_commit()[0] and "training" not in doc
    old = json.loads(results.dumps(doc))
    del old["meta"]["commit"]
    old["meta"].pop("modified", None)
    assert results.check(old) == old
    training = {
        "format": record.TRAINING, "row": "fast", "trainer": "t", "mode": "v0", "seed": 0, "command": ["py", "x"],
        "commit": "abc", "settings": {}, "steps": 10, "env_steps": 12, "train_seeds": [[0, 2], [5, 1]],
    }  # fmt: skip
    with_training = evaluate.run("heuristic", "v0", training=training, command=["python", "-m", "x"])
    assert with_training["training"] == training and with_training["meta"]["command"] == ["python", "-m", "x"]
    assert with_training["policy"]["train_seeds"] is None  # several ranges: in `training` only
    for broken, says in [
        ({**training, "train_seeds": [[999_999, 2]]}, "overlap the evaluation seeds"),
        ({**training, "mode": "full-v0"}, "`training.mode` is 'full-v0'"),
        ({**training, "command": "py x"}, "`training.command` must be a non-empty list"),
        ({k: v for k, v in training.items() if k != "settings"}, "`training.settings` is missing"),
    ]:
        bad = json.loads(results.dumps(with_training))
        bad["training"] = broken
        with pytest.raises(results.ResultsError, match=says):
            results.check(bad)
    bad = json.loads(results.dumps(doc))
    bad["meta"]["commit"] = "HEAD"
    with pytest.raises(results.ResultsError, match=r"meta\.commit"):
        results.check(bad)


def test_each_committed_trained_row_is_whole_training_seeds_0_to_9_named_alike():
    """A trained row (`MODE.ROW.seedS.json`, made by `bench row`) is committed whole: seeds 0-9, one name, ten
    different trained policies, each file's training seeds its own (S's games for the trainer and SB3)."""
    rows: dict[tuple[str, str], dict[int, dict]] = {}
    for f in RESULTS.glob("*.seed*.json"):
        mode, row, seed = f.name.removesuffix(".json").split(".")
        if row in TRAINED_ROWS:
            rows.setdefault((mode, row), {})[int(seed.removeprefix("seed"))] = json.loads(f.read_text())["policy"]
    assert {("sticky-v0", "fast"), ("full-v0", "fast"), ("sticky-v0", "sb3-ppo")} <= set(rows)
    for (mode, row), policies in rows.items():
        assert sorted(policies) == list(range(10)), f"{mode}.{row}: seeds {sorted(policies)}"
        assert len({p["name"] for p in policies.values()}) == 1
        assert len({p["sha256"] for p in policies.values()}) == 10
        assert len({tuple(p["train_seeds"]) for p in policies.values()}) == 10
        for seed, p in policies.items():
            if p["kind"] in ("recipe", "sb3"):
                assert p["train_seeds"][0] == seed, f"{mode}.{row}.seed{seed}: trained on {p['train_seeds']}"


def test_the_in_progress_results_are_valid_runs_of_trained_rows_not_yet_on_the_leaderboard():
    """docs/bench/in-progress/ holds the finished seeds of rows still being trained (`bench row --results` pointing
    there): each file is a valid results file of a trained row, named as `bench row` names it, and no (mode, row) of
    them is also on the leaderboard (a row moves there whole)."""
    files = sorted((ROOT / "docs" / "bench" / "in-progress").glob("*.json"))
    on_board = {tuple(f.name.split(".")[:2]) for f in RESULTS.glob("*.seed*.json")}
    for f in files:
        mode, row, seed = f.name.removesuffix(".json").split(".")
        assert row in TRAINED_ROWS and seed.removeprefix("seed").isdigit(), f.name
        data = results.load(f)
        assert data["mode"]["name"] == mode and data["policy"]["kind"] in ("recipe", "sb3", "onnx"), f.name
        assert (mode, row) not in on_board, f"{f.name}: its row is on the leaderboard; move the file there or drop it"


@pytest.mark.parametrize("page", ["docs/SPEC.md", "docs/site/bench.md", "docs/site/environment.md"])
def test_the_modes_tables_of_the_docs_are_the_cores(page):
    text = (ROOT / page).read_text()
    for m in chopperscape.MODES:
        line = next((x for x in text.splitlines() if x.startswith(f"| `{m['name']}` | `{m['id']}` |")), None)
        assert line is not None, f"{page} has no row for mode {m['name']}"
        options = line.split("|")[3]
        listed = [o.strip(" `") for o in options.split(",")] if m["options"] else []
        assert listed == [f"{k}={v}" for k, v in m["options"].items()] or (not listed and "(none)" in options)


def test_a_rows_training_record_is_what_its_trainer_wrote(tmp_path):
    """`bench row` reads each trainer's own account: SB3's `trainer.json`, RLlib's `--summary` (its runners' seed
    ranges, as RLlib seeded them), the recipe of `chopperscape.learn.train`."""
    from chopperscape.bench import record, rows

    made = {"settings": {"lr": 1}, "train_seeds": [[4 * 2**20, 128]], "env_steps": 99}
    (tmp_path / "summary.json").write_text(json.dumps(made))
    (tmp_path / "trainer.json").write_text(json.dumps({**made, "train_seeds": [[4, 1]]}))
    for key, seeds in (("rllib-ppo", [[4 * 2**20, 128]]), ("sb3-dqn", [[4, 1]])):
        t = rows.training_record(rows.ROWS[key], "full-v0", 3, 500, tmp_path, ["rpy", "-m", "x"])
        assert (t["train_seeds"], t["settings"], t["env_steps"], t["steps"]) == (seeds, {"lr": 1}, 99, 500)
        assert (t["row"], t["trainer"], t["commit"]) == (key, key, record.project_commit()[0])
    (tmp_path / "summary.json").write_text(json.dumps({**made, "train_seeds": [[999_990, 64]]}))
    with pytest.raises(ValueError, match="overlap the evaluation seeds"):
        rows.training_record(rows.ROWS["rllib-ppo"], "full-v0", 3, 500, tmp_path, ["rpy"])


def test_an_installed_package_run_in_its_checkout_records_the_checkouts_commit(tmp_path):
    """A wheel installed in a venv is tracked by no checkout: run from this checkout, whose `python/chopperscape`
    modules it holds byte for byte, it records the checkout's HEAD; with one module differing (an older wheel), the
    package version."""
    import chopperscape

    installed = tmp_path / "site" / "chopperscape"
    shutil.copytree(Path(chopperscape.__file__).parent, installed)
    for module in (ROOT / "python" / "chopperscape").rglob("*.py"):  # the checkout's sources, as its wheel has them
        target = installed / module.relative_to(ROOT / "python" / "chopperscape")
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(module, target)
    code = "from chopperscape.bench import record; print(record.__file__); print(record.project_commit()[0])"

    def commit(cwd: Path) -> list[str]:
        env = {**os.environ, "PYTHONPATH": str(installed.parent)}
        done = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, cwd=cwd, env=env, timeout=60
        )
        assert done.returncode == 0, done.stderr
        return done.stdout.split()

    head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    where, sha = commit(ROOT)
    assert where == str(installed / "bench" / "record.py") and sha == head
    assert commit(tmp_path)[1] == chopperscape.__version__  # not run in a checkout
    (installed / "bench" / "rows.py").write_text("# an older wheel\n")
    assert commit(ROOT)[1] == chopperscape.__version__
