"""ChopperScape-Bench, issue 44 part B: honest uncertainty (one-run rows get an interval over their episodes; every
row's run count is the protocol's; the mean return is exact) and joining (a callable policy gets its seed,
`--stochastic` and `--policy-arg`s, its declared files are hashed, a name taken with other settings is refused), and
the walk of "Adding a row" from a CleanRL-style script to a row, at a smoke budget."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import needs_torch

from chopperscape.bench import evaluate, report, results
from chopperscape.bench.__main__ import main as bench
from chopperscape.learn.stats import iqm

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "docs" / "bench" / "results"
FILES = sorted(str(p) for p in RESULTS.glob("*.json"))


def _rows(paths, **kw):
    return {r["policy"]: r for r in report.report(report.load_all(paths), resamples=kw.pop("resamples", 2000), **kw)}


def _err(capsys) -> str:
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1, captured.err
    return captured.err


# --- 1. honest uncertainty ---------------------------------------------------------------------------------------


def test_a_one_run_row_has_an_interval_over_its_episodes_stated_as_such():
    """The heuristic is one run: its interval is the percentile bootstrap of its mean over its 100 episodes (about
    ±0.031 on sticky-v0, as a t-interval of its episodes says too), never [x, x], and the table says so."""
    path = RESULTS / "sticky-v0.heuristic.json"
    row = _rows([str(path)], resamples=20_000)["heuristic @ sticky-v0"]
    doc = results.load(path)
    x = np.array([e["return"] for e in doc["episodes"]]) / 40_000
    half = 1.984 * x.std(ddof=1) / np.sqrt(len(x))  # the t-interval, for scale
    for name, a in row["aggregates"].items():
        assert a["low"] < a["point"] < a["high"], name
        if name != "optimality_gap":
            assert a["point"] == doc["summary"]["score"]
            assert abs((a["high"] - a["low"]) / 2 - half) < 0.1 * half, (a, half)
    assert row["interval_over"] == {"sticky-v0": "episodes"}
    line = report.markdown([row])
    assert "sticky-v0 (1 run: interval over its episodes)" in line
    # Rows of ten runs keep their intervals over runs, unchanged.
    ten = _rows([str(p) for p in sorted(RESULTS.glob("v0.random.seed*.json"))])["random @ v0"]
    assert ten["interval_over"] == {"v0": "runs"}
    tasks = [np.array([results.load(p)["summary"]["score"] for p in sorted(RESULTS.glob("v0.random.seed*.json"))])]
    assert ten["aggregates"] == report.interval_estimates(tasks, 2000)


def test_no_row_of_the_leaderboard_shows_an_interval_of_one_point():
    page = (ROOT / "docs" / "site" / "bench.md").read_text()
    table = [line for line in page.splitlines() if re.match(r"\| .* @ (v0|sticky-v0|full-v0) \|", line)]
    assert len(table) >= 19
    for line in table:
        for low, high in re.findall(r"\[([0-9.]+), ([0-9.]+)\]", line):
            assert low != high, line
        assert "partial" not in line, line


def test_every_row_the_report_prints_has_the_protocols_run_count(tmp_path, capsys):
    """Not a list of names: any row, named or not, of a stochastic policy or of several trained policies has ten
    runs; a deterministic policy alone has one. A row with another count is refused, naming it, or with
    --partial shown marked partial."""
    three_random = [str(RESULTS / f"v0.random.seed{k}.json") for k in range(3)]
    assert bench(["report", *three_random, "--resamples", "100"]) == 2
    assert "row 'random @ v0' has 3 runs on v0, and the protocol asks 10" in _err(capsys)
    three_trained = [str(RESULTS / f"sticky-v0.fast.seed{k}.json") for k in range(3)]
    assert bench(["report", *three_trained, "--resamples", "100"]) == 2
    assert "has 3 runs on sticky-v0, and the protocol asks 10 (" in _err(capsys)
    # Renamed to a name no list knows: still three of ten.
    renamed = []
    for k, f in enumerate(three_trained):
        doc = json.loads(Path(f).read_text())
        doc["policy"]["name"] = "my new row"
        renamed.append(str(tmp_path / f"n{k}.json"))
        Path(renamed[-1]).write_text(results.dumps(doc))
    assert bench(["report", *renamed, "--resamples", "100"]) == 2
    assert "row 'my new row @ sticky-v0' has 3 runs" in _err(capsys)
    assert bench(["report", *renamed, "--resamples", "100", "--partial"]) == 0
    assert "| my new row @ sticky-v0 | sticky-v0 (3 of 10 runs: partial) |" in capsys.readouterr().out
    # Pooled over modes, each mode is checked.
    pooled = [*three_random, str(RESULTS / "sticky-v0.random.seed0.json")]
    assert bench(["report", *pooled, "--pool-modes", "--resamples", "100"]) == 2
    assert "has 3 runs on v0" in _err(capsys)
    # The committed results: every row whole.
    rows = _rows(FILES, resamples=100)
    assert all(r["runs"] == r["runs_required"] for r in rows.values())
    assert rows["heuristic @ full-v0"]["runs_required"] == {"full-v0": 1}
    assert rows["models/ppo-features.pt @ v0"]["runs_required"] == {"v0": 1}
    assert rows["random @ sticky-v0"]["runs_required"] == {"sticky-v0": 10}


def test_the_mean_return_is_the_runs_exact_mean_not_the_rounded_score():
    rows = _rows(FILES, resamples=100)
    assert rows["heuristic @ full-v0"]["mean_return"] == {"full-v0": 7330.1}  # summary 7,330.14; score 0.183253
    by_row: dict[str, list[float]] = {}
    for f in FILES:
        doc = results.load(f)
        by_row.setdefault(f"{report._label(doc)} @ {doc['mode']['name']}", []).append(doc["summary"]["mean_return"])
    for label, means in by_row.items():
        (mode,) = rows[label]["mean_return"]
        assert abs(rows[label]["mean_return"][mode] - float(np.mean(means))) <= 0.05 + 1e-9, label


def test_the_iqm_of_ten_runs_is_the_mean_of_the_middle_six():
    x = np.array([0.0, 1, 2, 3, 4, 5, 6, 7, 8, 100])
    assert float(iqm(x)) == pytest.approx(np.mean(x[2:8])) == 4.5
    page = (ROOT / "docs" / "site" / "bench.md").read_text()
    assert "middle 6" in page and "middle 50 %" not in page


# --- 2. joining --------------------------------------------------------------------------------------------------

FACTORIES = """
import numpy as np

FILES = ["{table}"]


def factory(*, seed, stochastic=False, table, bias="0"):
    actions = np.loadtxt(table, dtype=np.int64).reshape(-1)
    rng = np.random.default_rng(seed)

    def act(obs):
        if stochastic:
            return rng.integers(0, 5, len(obs))
        return np.full(len(obs), actions[0] + int(bias))

    return act


def no_stochastic(*, seed, table):
    return lambda obs: np.full(len(obs), 3)
"""


@pytest.fixture
def factories(tmp_path, monkeypatch):
    (tmp_path / "my_factories.py").write_text(FACTORIES)
    (tmp_path / "table.txt").write_text("3\n")
    (tmp_path / "my_plain.py").write_text(
        "import numpy as np\n\n\ndef plain(obs):\n    return np.random.randint(0, 5, len(obs))\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_a_callable_factory_gets_its_seed_stochastic_and_arguments_and_its_files_are_hashed(factories, capsys):
    run = evaluate.run
    args = {"table": "table.txt"}
    s0 = run("my_factories:factory", "v0", stochastic=True, policy_seed=0, policy_args=args)
    s0b = run("my_factories:factory", "v0", stochastic=True, policy_seed=0, policy_args=args)
    s1 = run("my_factories:factory", "v0", stochastic=True, policy_seed=1, policy_args=args)
    assert s0["episodes"] == s0b["episodes"] != s1["episodes"]  # seeded by --policy-seed
    assert s0["policy"]["actions"] == "sampled" and s0["policy"]["args"] == args
    greedy = run("my_factories:factory", "v0", policy_args={**args, "bias": "0"})
    assert greedy["policy"]["actions"] == "greedy" and greedy["policy"]["args"] == {"table": "table.txt", "bias": "0"}
    assert [f[0] for f in greedy["policy"]["files"]][1:] == ["table.txt"]
    (factories / "table.txt").write_text("3\n\n")  # the same actions, another file: another hash
    again = run("my_factories:factory", "v0", policy_args={**args, "bias": "0"})
    assert again["episodes"] == greedy["episodes"] and again["policy"]["sha256"] != greedy["policy"]["sha256"]
    # A plain callable drawing from numpy's global generator draws from one seeded by the run.
    p0, p0b = run("my_plain:plain", "v0", policy_seed=0), run("my_plain:plain", "v0", policy_seed=0)
    assert p0["episodes"] == p0b["episodes"] != run("my_plain:plain", "v0", policy_seed=1)["episodes"]
    for argv, says in [
        (["my_factories:no_stochastic", "--stochastic", "--policy-arg", "table=table.txt"], "--stochastic: policy"),
        (["my_plain:plain", "--stochastic"], "cannot be asked to sample"),
        (["my_plain:plain", "--policy-arg", "table=table.txt"], "takes no arguments"),
        (["my_factories:factory", "--policy-arg", "table=table.txt", "--policy-arg", "x=1"], "--policy-arg x:"),
        (["my_factories:factory"], "FILES entry '{table}' names a policy argument not given"),
        (["my_factories:factory", "--policy-arg", "table=nope.txt"], "its declared file 'nope.txt'"),
        (["heuristic", "--policy-arg", "table=table.txt"], "--policy-arg is for a callable policy"),
        (["my_factories:factory", "--policy-arg", "seed=1"], "other than seed and stochastic"),
    ]:
        assert bench(["evaluate", *argv, "--mode", "v0"]) == 2, argv
        assert says in _err(capsys), argv
    with pytest.raises(SystemExit):
        bench(["evaluate", "my_factories:factory", "--mode", "v0", "--policy-arg", "table"])
    # What is recorded is checked.
    bad = json.loads(results.dumps(greedy))
    bad["policy"]["args"] = {"table": 3}
    with pytest.raises(results.ResultsError, match=r"policy\.args"):
        results.check(bad)
    bad = json.loads(results.dumps(run("heuristic", "v0")))
    bad["policy"]["args"] = {}
    with pytest.raises(results.ResultsError, match="a callable policy's only"):
        results.check(bad)


def test_a_name_taken_with_other_settings_is_refused_with_both_named(factories, capsys):
    folder = factories / "results"
    folder.mkdir()
    first = folder / "a.json"
    assert bench(["evaluate", "heuristic", "--mode", "v0", "--name", "my row", "--out", str(first)]) == 0
    second = folder / "b.json"
    argv = ["evaluate", "my_factories:factory", "--mode", "v0", "--policy-arg", "table=table.txt", "--name", "my row"]
    assert bench([*argv, "--out", str(second)]) == 2  # into the folder where the name is the heuristic's
    err = _err(capsys)
    assert str(first) in err and str(second) in err and '"builtin"' in err and '"callable"' in err, err
    assert not second.exists()
    elsewhere = factories / "b.json"
    assert bench([*argv, "--out", str(elsewhere)]) == 0
    assert bench(["report", str(first), str(elsewhere), "--resamples", "100", "--partial"]) == 2
    err = _err(capsys)
    assert "row 'my row'" in err and str(first) in err and str(elsewhere) in err
    assert 'source "heuristic"' in err and 'source "my_factories:factory"' in err, err
    # Greedy and sampled under one name: another setting, refused too.
    sampled = factories / "c" / "c.json"
    sampled.parent.mkdir()
    assert bench([*argv, "--stochastic", "--out", str(sampled)]) == 0
    assert bench(["report", str(elsewhere), str(sampled), "--resamples", "100", "--partial"]) == 2
    assert 'actions "greedy"' in _err(capsys)
    # The observation played is a setting.
    obs = factories / "d" / "d.json"
    obs.parent.mkdir()
    assert bench([*argv, "--option", "keep_dim=true", "--out", str(obs)]) == 0
    assert bench(["report", str(elsewhere), str(obs), "--resamples", "100", "--partial"]) == 2
    assert "observation" in _err(capsys)


# --- 3. "Adding a row", end to end at a smoke budget -------------------------------------------------------------


@needs_torch
def test_a_cleanrl_style_agent_becomes_a_row(tmp_path):
    """docs/site/bench.md's walk: train `python/examples/cleanrl_ppo.py` (two seeds, 2,048 decisions), evaluate its
    saved weights through `cleanrl_policy:policy` under the row's name, then `bench report`: two of ten runs
    are refused, and shown marked partial with --partial."""
    # Only the examples folder on the path: `python/` itself would shadow the installed package with its sources,
    # which lack the compiled `_core` in a clean clone.
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(ROOT / "python" / "examples"), os.environ.get("PYTHONPATH", "")]),
    }
    out = tmp_path / "results"
    out.mkdir()
    name = "CleanRL-style PPO, 2,048 decisions"
    for seed in (0, 1):
        run = tmp_path / f"seed-{seed}"
        train = [sys.executable, str(ROOT / "python" / "examples" / "cleanrl_ppo.py"), "--mode", "sticky-v0"]
        train += ["--seed", str(seed), "--steps", "2048", "--envs", "4", "--out", str(run)]
        done = subprocess.run(train, capture_output=True, text=True, env=env, timeout=600)
        assert done.returncode == 0, done.stderr
        assert json.loads((run / "train.json").read_text())["train_seeds"] == [seed, 4]
        ev = [sys.executable, "-m", "chopperscape.bench", "evaluate", "cleanrl_policy:policy"]
        ev += ["--mode", "sticky-v0", "--policy-arg", f"weights={run / 'weights.pt'}", "--train-seeds", f"{seed}:4"]
        ev += ["--name", name, "--out", str(out / f"sticky-v0.cleanrl.seed{seed}.json")]
        done = subprocess.run(ev, capture_output=True, text=True, env=env, timeout=600, cwd=tmp_path)
        assert done.returncode == 0, done.stderr
    docs = [results.load(out / f"sticky-v0.cleanrl.seed{s}.json") for s in (0, 1)]
    for seed, d in enumerate(docs):
        pol = d["policy"]
        assert pol["kind"] == "callable" and pol["name"] == name and pol["train_seeds"] == [seed, 4]
        assert pol["args"] == {"weights": str(tmp_path / f"seed-{seed}" / "weights.pt")}
        assert pol["files"][1] == [pol["args"]["weights"], evaluate._atomic.sha256(pol["args"]["weights"])]
    assert docs[0]["policy"]["sha256"] != docs[1]["policy"]["sha256"]
    rep = [sys.executable, "-m", "chopperscape.bench", "report", *map(str, sorted(out.glob("*.json")))]
    done = subprocess.run([*rep, "--resamples", "200"], capture_output=True, text=True, env=env, timeout=600)
    assert done.returncode == 2 and "has 2 runs on sticky-v0, and the protocol asks 10" in done.stderr
    done = subprocess.run([*rep, "--resamples", "200", "--partial"], capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    assert f"| {name} @ sticky-v0 | sticky-v0 (2 of 10 runs: partial) |" in done.stdout
