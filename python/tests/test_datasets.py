"""Minari datasets: written through Minari's storage, read back by `minari.load_dataset`, equal to a replay of
their seeds step for step; from policies and from `play --save-actions` logs."""

from __future__ import annotations

import json
import pathlib
import subprocess

import gymnasium as gym
import numpy as np
import pytest

from chopperscape import policies

minari = pytest.importorskip("minari", reason="minari is not installed (pip install 'minari[hdf5]' pillow)")
pytest.importorskip("h5py", reason="h5py is not installed (pip install 'minari[hdf5]')")
pytest.importorskip("PIL", reason="pillow is not installed (Minari's HDF5 storage imports it)")
from test_policies import cli  # noqa: E402

from chopperscape.integrations import datasets  # noqa: E402
from chopperscape.integrations.datasets import cli as datasets_cli  # noqa: E402


@pytest.fixture(autouse=True)
def datasets_path(tmp_path, monkeypatch):
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    return tmp_path / "minari"


def replay_equals(ds, options, limit):
    """Every episode of `ds` equals a replay of its seed with its actions."""
    env = gym.make("ChopperScape-v0", max_episode_steps=limit, **options)
    seeds = [m["seed"] for m in ds.storage.get_episode_metadata(range(ds.total_episodes))]
    for seed, ep in zip(seeds, ds.iterate_episodes()):
        obs, _ = env.reset(seed=seed)
        observations, rewards, terms, truncs = [obs], [], [], []
        for a in ep.actions:
            obs, r, te, tr, _ = env.step(int(a))
            observations.append(obs)
            rewards.append(r)
            terms.append(te)
            truncs.append(tr)
        np.testing.assert_array_equal(ep.observations, np.stack(observations))
        np.testing.assert_array_equal(ep.rewards, rewards)
        np.testing.assert_array_equal(ep.terminations, terms)
        if not truncs[-1] and not terms[-1]:
            truncs[-1] = True  # an episode stopped early ends truncated, as Minari's DataCollector marks it
        np.testing.assert_array_equal(ep.truncations, truncs)
    return seeds


@pytest.mark.parametrize(
    "options",
    [
        {"obs_type": "features"},
        {"obs_type": "grayscale", "obs_size": (42, 42), "frame_skip": 2, "sticky_prob": 0.25},
        {"obs_type": "rgb", "obs_size": (24, 32), "hud": False, "frame_stack": 2, "lives": 2, "alien_prob": 0.02},
    ],
    ids=["features", "grayscale", "rgb"],
)
def test_collected_dataset_loads_with_minari_and_equals_a_replay(options):
    ds = datasets.collect("cs/test-v0", "heuristic", 3, 7, max_episode_steps=250, chunk_steps=64, **options)
    back = minari.load_dataset("cs/test-v0")
    assert back.total_episodes == 3 and back.total_steps == ds.total_steps
    assert replay_equals(back, options, 250) == [7, 8, 9]
    # The actions are the policy's, exactly as `chopperscape demo` plays those seeds.
    expected = [e["actions"] for e in policies.episodes("heuristic", 3, 7, max_episode_steps=250, **options)]
    assert [list(ep.actions) for ep in back.iterate_episodes()] == expected
    meta = back.storage.metadata
    assert meta["policy"] == "heuristic" and meta["seeds"] == [7, 8, 9]
    assert meta["chopperscape_version"] == datasets._core.__version__
    assert (meta["features_version"], meta["pixels_version"]) == (2, 3)
    assert meta["max_episode_steps"] == 250 and meta["jpeg_encoding"] is False
    assert back.spec.env_spec.kwargs["obs_type"] == options["obs_type"]
    # Minari rebuilds the env from the stored spec.
    env = back.recover_environment()
    assert env.observation_space == back.observation_space


def test_an_existing_dataset_is_never_overwritten_and_bad_input_writes_nothing(datasets_path):
    datasets.collect("cs/once-v0", "noop", 1, 0, obs_type="features", max_fuel=30)
    with pytest.raises(ValueError, match="already exists"):
        datasets.collect("cs/once-v0", "noop", 1, 0, obs_type="features")
    with pytest.raises(ValueError, match="unknown policy 'genius'"):
        datasets.collect("cs/other-v0", "genius", 1)
    with pytest.raises(ValueError, match="Malformed dataset ID"):
        datasets.collect("no version", "noop", 1)
    with pytest.raises(ValueError, match="option `episodes`"):
        datasets.collect("cs/other-v0", "noop", 0)
    with pytest.raises(ValueError, match="lives"):
        datasets.collect("cs/other-v0", "noop", 1, lives=0)
    assert sorted(p.name for p in (datasets_path / "cs").iterdir()) == ["namespace_metadata.json", "once-v0"]


def write_log(path: pathlib.Path, seed: int, actions: list[int], ret, cause, options: dict) -> None:
    """An action log in the format of crates/cli/src/actionlog.rs."""
    doc = {
        "format": "chopperscape-actions",
        "version": 1,
        "env": "ChopperScape-v0",
        "seed": seed,
        "options": options,
        "policy": "human",
        "steps": len(actions),
        "return": ret,
        "cause": cause,
        "actions": "".join(map(str, actions)),
    }
    path.write_text(json.dumps(doc))


RULES = {"lives": "2", "max_fuel": "80", "bird_prob": "0.05", "max_episode_steps": "10000"}


def test_action_logs_become_dataset_episodes(tmp_path):
    opts = {k: v for k, v in RULES.items() if k != "max_episode_steps"}
    full = next(policies.episodes("random", 1, 3, **opts))
    write_log(tmp_path / "a.json", 3, full["actions"], full["return"], full["cause"], RULES)
    # A human who pressed Esc after 20 steps: the episode stops there, its last step truncated.
    part = next(policies.episodes("heuristic", 1, 5, **opts))
    write_log(tmp_path / "b.json", 5, part["actions"][:20], 20, None, RULES)
    logs = [tmp_path / "a.json", tmp_path / "b.json"]
    exe = cli()
    if exe is not None:  # a log the command line itself wrote
        subprocess.run(
            [
                str(exe),
                "record",
                "--policy",
                "random",
                "--seed",
                "9",
                "--lives",
                "2",
                "--max-fuel",
                "80",
                "--bird-prob",
                "0.05",
                "--out",
                str(tmp_path / "c.gif"),
                "--save-actions",
                str(tmp_path / "c.json"),
            ],
            check=True,
            capture_output=True,
        )
        logs.append(tmp_path / "c.json")
    ds = datasets.from_action_logs("cs/human-v0", logs, obs_type="grayscale", obs_size=(32, 32), chunk_steps=7)
    back = minari.load_dataset("cs/human-v0")
    assert back.total_episodes == len(logs)
    assert replay_equals(back, {**opts, "obs_type": "grayscale", "obs_size": (32, 32)}, 10_000)[:2] == [3, 5]
    eps = list(back.iterate_episodes())
    assert len(eps[1].actions) == 20 and eps[1].truncations[-1] and not eps[1].terminations.any()
    # Human play only is "human"; the CLI's log here was played by the random policy.
    assert ds.storage.metadata["algorithm_name"] == ("human" if exe is None else "action-logs")


def test_action_logs_that_do_not_replay_are_refused_and_write_nothing(tmp_path, datasets_path):
    write_log(tmp_path / "a.json", 3, [4] * 30, 999, "bird", RULES)
    with pytest.raises(ValueError, match="not played under these rules; nothing was written"):
        datasets.from_action_logs("cs/bad-v0", [tmp_path / "a.json"], obs_type="features")
    assert not (datasets_path / "cs" / "bad-v0").exists()
    (tmp_path / "b.json").write_text('{"format": "other"}')
    with pytest.raises(ValueError, match=r"b\.json is not a usable action log"):
        datasets.from_action_logs("cs/bad-v0", [tmp_path / "b.json"])
    write_log(tmp_path / "c.json", 3, [4] * 30, 30, None, {**RULES, "lives": "3"})
    write_log(tmp_path / "d.json", 3, [4] * 30, 30, None, RULES)
    with pytest.raises(ValueError, match="other options"):
        datasets.from_action_logs("cs/bad-v0", [tmp_path / "c.json", tmp_path / "d.json"])
    with pytest.raises(ValueError, match="change the rules"):
        datasets.from_action_logs("cs/bad-v0", [tmp_path / "d.json"], lives=3)


def test_the_module_command_line_writes_a_dataset(datasets_path, capsys):
    rc = datasets_cli.main(
        [
            "--out",
            "cs/cli-v0",
            "--policy",
            "random",
            "--episodes",
            "2",
            "--seed",
            "4",
            "--option",
            "obs_type=features",
            "--option",
            "max_episode_steps=100",
            "--no-progress",
        ]
    )
    assert rc == 0, capsys.readouterr().err
    ds = minari.load_dataset("cs/cli-v0")
    assert ds.total_episodes == 2 and ds.storage.metadata["seeds"] == [4, 5]
    assert datasets_cli.main(["--out", "cs/cli-v0", "--episodes", "1", "--no-progress"]) == 2
    assert "already exists" in capsys.readouterr().err


def test_the_cli_dataset_command_runs_the_python_package(datasets_path, tmp_path):
    import os
    import sys

    exe = cli()
    if exe is None:
        pytest.skip("cargo is not installed: the `chopperscape dataset` command is not built")
    env = {**os.environ, "CHOPPERSCAPE_PYTHON": sys.executable}
    args = [
        str(exe),
        "dataset",
        "--policy",
        "heuristic",
        "--episodes",
        "2",
        "--seed",
        "3",
        "--obs-type",
        "features",
        "--max-episode-steps",
        "120",
        "--frame-skip",
        "2",
        "--out",
        "cs/from-cli-v0",
    ]
    done = subprocess.run(args, env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    ds = minari.load_dataset("cs/from-cli-v0")
    assert ds.storage.metadata["seeds"] == [3, 4]
    replay_equals(ds, {"obs_type": "features", "frame_skip": "2"}, 120)
    expected = [e["actions"] for e in policies.episodes("heuristic", 2, 3, max_episode_steps=120, frame_skip=2)]
    assert [list(ep.actions) for ep in ds.iterate_episodes()] == expected
    # An existing dataset: a usage error from the package, exit code 2.
    again = subprocess.run(args, env=env, capture_output=True, text=True)
    assert again.returncode == 2 and "already exists" in again.stderr
    # An interpreter without the package: a clear message, exit code 1.
    bare = tmp_path / "bare-python"
    bare.write_text('#!/bin/sh\nexec /usr/bin/env python3 -I -S "$@"\n')
    bare.chmod(0o755)
    missing = subprocess.run(
        args[:-1] + ["cs/never-v0"], env={**env, "CHOPPERSCAPE_PYTHON": str(bare)}, capture_output=True, text=True
    )
    assert missing.returncode == 1
    assert "cannot import chopperscape.integrations.datasets" in missing.stderr and "pip install" in missing.stderr
    assert not (datasets_path / "cs" / "never-v0").exists()


def test_collection_streams_to_disk_with_bounded_memory():
    import tracemalloc

    def peak(dataset_id: str, chunk_steps: int) -> int:
        tracemalloc.start()
        try:
            datasets.collect(
                dataset_id,
                "noop",
                1,
                0,
                obs_type="grayscale",
                obs_size=(84, 84),
                bird_prob=0,
                max_episode_steps=1000,
                chunk_steps=chunk_steps,
            )
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    # 1000 observations of 84 × 84 bytes are 7 MB: held in chunks of 50, a small fraction of that is ever alive.
    peak("cs/warm-up-v0", 50)  # the first collection imports modules, which tracemalloc counts too
    streamed, whole = peak("cs/chunked-v0", 50), peak("cs/whole-v0", 10_000)
    assert streamed < 2_500_000 < 7_000_000 < whole, (streamed, whole)
    a, b = minari.load_dataset("cs/chunked-v0"), minari.load_dataset("cs/whole-v0")
    ea, eb = next(a.iterate_episodes()), next(b.iterate_episodes())
    assert ea.observations.shape == (1001, 84, 84)
    np.testing.assert_array_equal(ea.observations, eb.observations)
