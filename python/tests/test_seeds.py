"""Several seeds, reported as the field does (`chopperscape.learn.seeds`, `.summary`, `.stats`): the IQM and its
bootstrap interval by their definitions, the runner end to end (train, evaluate, resume, summarise), and other
trainers' files summarised the same way."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from conftest import needs_torch


def test_iqm_and_bootstrap_match_their_definitions():
    from chopperscape.learn.seeds import parse_seeds
    from chopperscape.learn.stats import bootstrap_ci, iqm

    assert parse_seeds("0-3,7, 2") == [0, 1, 2, 3, 7] and parse_seeds("1,0,2-3") == [1, 0, 2, 3]
    for bad in ("", "a", "3-1", "-1", "0-5000"):
        with pytest.raises(ValueError, match=r"^--seeds"):
            parse_seeds(bad)
    # At most 1000 seeds a range, wherever it starts (boundaries from the mutation pass).
    assert len(parse_seeds("0-999")) == 1000 and parse_seeds("600-700")[-1] == 700
    with pytest.raises(ValueError, match=r"^--seeds '0-1000': '0-1000' must be 0 <= FIRST <= LAST with at most 1000"):
        parse_seeds("0-1000")
    x = np.array([100.0, 1, 2, 3, 4, 5, 6, 7, 8, -50])
    # scipy.stats.trim_mean(x, 0.25): drop int(0.25 * 10) = 2 from each end.
    assert iqm(x) == pytest.approx(np.mean([2, 3, 4, 5, 6, 7]))
    assert iqm(np.arange(8.0)) == pytest.approx(np.mean([2, 3, 4, 5]))
    lo, hi = bootstrap_ci(x, resamples=4000)
    assert lo < iqm(x) < hi and lo >= -50 and hi <= 100
    assert bootstrap_ci(x, resamples=4000) == (lo, hi)  # seeded: a summary is reproducible
    assert bootstrap_ci(np.full(6, 7.0), resamples=100) == (7.0, 7.0)
    with pytest.raises(ValueError, match=r"^--seeds '0-999,1000': at most 1000 seeds$"):
        parse_seeds("0-999,1000")
    # The percentile bootstrap by its definition: resample the runs with replacement (numpy's generator, seeded),
    # take the statistic of each resample, and the 2.5th and 97.5th percentiles of those.
    rng = np.random.default_rng(3)
    idx = rng.integers(0, len(x), size=(1000, len(x)))
    ref = np.percentile([iqm(x[i]) for i in idx], [2.5, 97.5])
    assert bootstrap_ci(x, resamples=1000, seed=3) == tuple(ref)
    assert bootstrap_ci(x, resamples=1000, level=0.5, seed=3) == tuple(
        np.percentile([iqm(x[i]) for i in idx], [25.0, 75.0])
    )
    # With a statistic that is not stepped (the mean), every percentile and the default seed 0 show.
    idx0 = np.random.default_rng(0).integers(0, len(x), size=(1000, len(x)))
    means = x[idx0].mean(axis=-1)
    assert np.allclose(bootstrap_ci(x, stat=np.mean, resamples=1000), np.percentile(means, [2.5, 97.5]), atol=1e-9)
    assert np.allclose(
        bootstrap_ci(x, stat=np.mean, resamples=1000, level=0.8), np.percentile(means, [10, 90]), atol=1e-9
    )
    # The protocol the docs state: 100 held-out seeds from 1,000,000; rliable's 50,000 resamples, 95 %, seed 0.
    from chopperscape.learn import seeds, stats

    assert (seeds.EVAL_EPISODES, seeds.EVAL_SEED, stats.RESAMPLES) == (100, 1_000_000, 50_000)
    assert bootstrap_ci(x) == bootstrap_ci(x, resamples=50_000, level=0.95, seed=0)
    # `python -m chopperscape.learn.seeds` is a command (its --help needs no training).
    out = subprocess.run([sys.executable, "-m", "chopperscape.learn.seeds", "--help"], capture_output=True, text=True)
    assert out.returncode == 0 and "--seeds SEEDS" in out.stdout, out.stderr
    # Curves: points along the first axis are bootstrapped together, one interval per point.
    lo2, hi2 = bootstrap_ci(np.stack([x, x + 10]), resamples=4000)
    assert np.allclose(lo2, [lo, lo + 10]) and np.allclose(hi2, [hi, hi + 10])


@needs_torch
def test_seeds_runner_smoke_trains_evaluates_resumes_and_summarises(tmp_path, capsys):
    from chopperscape.learn import seeds

    out = tmp_path / "bench"
    args = [
        "--seeds",
        "0-1",
        "--steps",
        "2000",
        "--out",
        str(out),
        "--eval-episodes",
        "3",
        "--jobs",
        "2",
        "--num-envs",
        "8",
        "--num-steps",
        "64",
        "--hidden",
        "16",
        "--option",
        "max_fuel=150",
    ]
    assert seeds.main(args) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["seeds"] == [0, 1] and set(summary["per_seed"]) == {"0", "1"}
    means = [summary["per_seed"][s]["mean_return"] for s in ("0", "1")]
    lo, hi = summary["iqm_ci95"]
    assert lo <= summary["iqm"] <= hi and min(means) <= lo and hi <= max(means)
    assert summary["eval"] == {"episodes": 3, "seed": 1_000_000}
    assert set(summary["baselines"]) == {"random", "heuristic"}
    # The options reached training and every evaluation: max_fuel 150 bounds the policies' episodes without tanks.
    assert json.loads((out / "seed-1" / "recipe.json").read_text())["env_options"] == {"max_fuel": 150}
    assert "IQM" in (out / "summary.md").read_text() and "| 1 |" in (out / "summary.md").read_text()
    # Run again: every seed is already evaluated with these settings, so nothing is retrained.
    stamp = (out / "seed-0" / "model.pt").stat().st_mtime_ns
    assert seeds.main(args) == 0 and (out / "seed-0" / "model.pt").stat().st_mtime_ns == stamp
    assert json.loads((out / "summary.json").read_text()) == summary


def test_seeds_summarise_reads_another_trainers_evaluations_and_refuses_mismatches(tmp_path, capsys):
    """`--summarise DIR`: the SB3 and RLlib rows get the recipe's statistics from their own files."""
    from chopperscape.learn import seeds, stats

    folder = tmp_path / "rllib"
    folder.mkdir()
    means = {0: 3425.6, 1: 900.0, 2: 5100.0, 3: 4000.0}
    for k, m in means.items():
        result = {"seed": 1_000_000, "episodes": 3, "mean_return": m, "std_return": 10.0, "min_return": int(m) - 5}
        result |= {"max_return": int(m) + 5, "mean_steps": m, "causes": {"bird": 1.0}}
        (folder / f"seed-{k}.eval.json").write_text(json.dumps(result))
        (folder / f"seed-{k}.csv").write_text("env_steps,wall_s,episodes,mean_return\n100,1,1,5\n200,2,2,9\n")
    (folder / "seed-x.eval.json").write_text("{}")  # not a seed's: ignored
    args = ["--summarise", str(folder), "--steps", "200", "--eval-episodes", "3", "--title", "RLlib PPO"]
    assert seeds.main(args) == 0
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["seeds"] == [0, 1, 2, 3] and summary["steps"] == 200
    assert summary["iqm"] == round(float(stats.iqm(np.array(list(means.values())))), 1) == 3712.8
    assert summary["min"] == 900.0 and set(summary["baselines"]) == {"random", "heuristic"}
    assert (folder / "baseline-heuristic.json").is_file() and "| 3 | 4,000 ± 10 |" in (
        folder / "summary.md"
    ).read_text()
    capsys.readouterr()
    # Evaluations of other held-out seeds, a missing curve, an empty folder, training flags: refused, named.
    assert seeds.main(["--summarise", str(folder), "--steps", "200"]) == 2
    assert "played 3 episodes from seed 1000000; this summary is of 100 from 1000000" in capsys.readouterr().err
    (folder / "seed-2.csv").unlink()
    assert seeds.main(args) == 2 and "seed-2.csv missing" in capsys.readouterr().err
    assert seeds.main(["--summarise", str(tmp_path / "none"), "--eval-episodes", "3"]) == 2
    assert "has no seed-K.eval.json" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        seeds.main([*args, "--seeds", "0-1"])
    assert "--summarise DIR takes no --seeds" in capsys.readouterr().err


def test_seeds_summarise_plays_the_baselines_under_the_presets_rules(tmp_path, capsys):
    """`--summarise DIR --preset P`: the baselines play P's frame skip, as the runner plays them for P's seeds (the
    heuristic at frame skip 1 scores half what it scores at 4), and P's budget is the summary's; flags that are not
    the rules are refused by name, and nothing is written."""
    from chopperscape.learn import seeds

    folder = tmp_path / "pixels"
    folder.mkdir()
    result = {"seed": 1_000_000, "episodes": 2, "mean_return": 900.0, "std_return": 1.0, "min_return": 899}
    result |= {"max_return": 901, "mean_steps": 900.0, "causes": {"bird": 1.0}}
    (folder / "seed-0.eval.json").write_text(json.dumps(result))
    (folder / "seed-0.csv").write_text("env_steps,wall_s,episodes,mean_return\n100,1,1,5\n")
    for refused, named in [
        (["--preset", "pixels", "--ent-coef", "0.02"], "--summarise DIR takes no"),
        (["--option", "obs_size=[42,42]"], "--option obs_size does not change the game's rules"),
    ]:
        with pytest.raises(SystemExit):
            seeds.main(["--summarise", str(folder), "--eval-episodes", "2", *refused])
        assert named in capsys.readouterr().err and not (folder / "summary.json").exists()
    assert seeds.main(["--summarise", str(folder), "--eval-episodes", "2", "--preset", "pixels"]) == 0
    heuristic = json.loads((folder / "baseline-heuristic.json").read_text())
    assert heuristic["runner"]["option"] == ["frame_skip=4"]
    assert json.loads((folder / "summary.json").read_text())["steps"] == 12_000_000
    # The same folder under other rules: the cached baselines are played again under them, not reused.
    assert seeds.main(["--summarise", str(folder), "--eval-episodes", "2", "--option", "lives=3"]) == 0
    heuristic = json.loads((folder / "baseline-heuristic.json").read_text())
    assert heuristic["runner"]["option"] == ["lives=3"] and heuristic["mean_return"] > 0


def test_seeds_runner_trains_with_the_command_line_when_given_cli(tmp_path, capsys):
    """`--cli PATH`: each seed is trained by `PATH train` (the Rust learner) and its `model.onnx` played by `PATH demo
    --json` on the held-out seeds, summarised as `evaluate` summarises; only --preset is passed on. A stand-in
    command line records how it was called and writes what the real one writes."""
    from chopperscape.learn import seeds

    calls = tmp_path / "calls.txt"
    cli = tmp_path / "chopperscape"
    cli.write_text(
        f"""#!{sys.executable}
import json, pathlib, sys
args = sys.argv[1:]
with open({str(calls)!r}, "a") as f:
    f.write(" ".join(args) + "\\n")
if args[0] == "train":
    out = pathlib.Path(args[args.index("--out") + 1])
    seed = int(args[args.index("--seed") + 1])
    (out / "model.onnx").write_bytes(b"onnx")
    (out / "progress.csv").write_text("env_steps,wall_s,episodes,mean_return\\n100,1,1,5\\n200,2,2,%d\\n" % (9 + seed))
else:
    first = int(args[args.index("--seed") + 1])
    for k in range(int(args[args.index("--episodes") + 1])):
        ret = 100 * (k + 1) + first % 7
        cause = "bird" if k % 2 else "fuel"
        print(json.dumps({{"episode": k, "seed": first + k, "steps": ret // 4, "return": ret, "cause": cause}}))
"""
    )
    cli.chmod(0o755)
    out = tmp_path / "rust"
    args = ["--cli", str(cli), "--preset", "fast", "--seeds", "0-1", "--steps", "2000", "--out", str(out)]
    args += ["--eval-episodes", "4", "--jobs", "1"]
    assert seeds.main(args) == 0
    lines = calls.read_text().splitlines()
    assert f"train --out {out / 'seed-0'} --seed 0 --steps 2000 --force --preset fast" in lines
    assert f"demo --policy {out / 'seed-1' / 'model.onnx'} --episodes 4 --seed 1000000 --json" in lines
    result = json.loads((out / "seed-0" / "eval.json").read_text())
    # Returns 100..400 (+ 1000000 % 7 = 1): the summary `evaluate` writes, with each episode.
    assert result["mean_return"] == 251.0 and result["min_return"] == 101 and result["max_return"] == 401
    assert result["causes"] == {"bird": 0.5, "fuel": 0.5} and result["episodes"] == 4
    assert [e["seed"] for e in result["per_episode"]] == [1_000_000 + k for k in range(4)]
    assert result["runner"]["trainer"] == "rust"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["seeds"] == [0, 1] and summary["iqm"] == 251.0
    # The baselines play the preset's rules (frame skip 4), as the seeds were trained and evaluated.
    assert json.loads((out / "baseline-heuristic.json").read_text())["runner"]["option"] == ["frame_skip=4"]
    # Finished seeds are not trained again.
    before = len(calls.read_text().splitlines())
    assert seeds.main(args) == 0 and len(calls.read_text().splitlines()) == before
    capsys.readouterr()
    # Flags the Rust learner does not take, and a --cli that is not a program: refused before anything runs.
    for bad, says in (
        (["--ent-coef", "0.02"], "only --preset NAME is passed on, not --preset fast --ent-coef 0.02"),
        (["--option", "max_fuel=150"], "only --preset NAME is passed on"),
    ):
        with pytest.raises(SystemExit) as e:
            seeds.main([*args, *bad])
        assert e.value.code == 2 and says in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:
        seeds.main(["--cli", str(tmp_path / "none"), "--seeds", "0", "--out", str(out)])
    assert e.value.code == 2 and "not an executable file" in capsys.readouterr().err
    assert len(calls.read_text().splitlines()) == before
