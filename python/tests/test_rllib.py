"""Ray RLlib (new API stack): ChopperScape-v0 by name in RLlib's env runners, the native batch per runner, seeds
distinct across runners and sub-envs, and PPO on a real local Ray cluster (`ray start --head` on loopback),
driven by python/examples/rllib_ppo.py through `--address`.

Ray pins its own Gymnasium, so scripts/test-python.sh runs this file in a second environment (.venv-rllib);
elsewhere it is skipped.
"""

from __future__ import annotations

import csv
import importlib.util
import json
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip(
    "ray", reason="Ray is not installed: pip install 'ray[rllib]' torch (scripts/test-python.sh does, into .venv-rllib)"
)
pytest.importorskip("ray.rllib", reason="RLlib is not installed: pip install 'ray[rllib]' torch")
pytest.importorskip("torch", reason="torch is not installed (RLlib's PPO needs it): pip install torch")

import gymnasium as gym
from ray.rllib.algorithms.ppo import PPOConfig
from ray.rllib.env.env_context import EnvContext
from ray.rllib.env.single_agent_env_runner import SingleAgentEnvRunner

import chopperscape
import chopperscape.integrations.rllib as crl
from chopperscape.learn import progress

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "python" / "examples" / "rllib_ppo.py"
K = crl.SEED_STRIDE
FEATURES = {"obs_type": "features"}


def test_importing_chopperscape_does_not_import_ray():
    code = "import sys, chopperscape; assert not any(m == 'ray' or m.startswith('ray.') for m in sys.modules)"
    subprocess.run([sys.executable, "-c", code], check=True, timeout=60)


def test_vector_creator_builds_the_native_batch_and_remaps_seeds():
    env = crl.env_creator({**FEATURES, "num_envs": 3, "lives": 2})
    assert isinstance(env.unwrapped, chopperscape.VectorEnv)
    assert env.num_envs == 3 and env.unwrapped._options["lives"] == 2
    obs, _ = env.reset(seed=5)
    assert env.reset_seeds == [5 * K, 5 * K + 1, 5 * K + 2]
    for i, seed in enumerate(env.reset_seeds):
        single = gym.make("ChopperScape-v0", lives=2, **FEATURES)
        np.testing.assert_array_equal(obs[i], single.reset(seed=seed)[0])


def test_single_creator_is_a_time_limited_env_seeded_by_its_runner():
    env = crl.env_creator(EnvContext({**FEATURES, "num_threads": 2}, worker_index=3, num_workers=4))
    assert env.spec.max_episode_steps == 10_000
    obs, _ = env.reset(seed=7)
    assert env.reset_seed == 7 * K + 3
    np.testing.assert_array_equal(obs, gym.make("ChopperScape-v0", **FEATURES).reset(seed=7 * K + 3)[0])


def test_creator_takes_lists_from_json_configs_as_tuples():
    env = crl.env_creator({"num_envs": 2, "obs_type": "grayscale", "obs_size": [84, 84], "frame_stack": 4})
    assert env.single_observation_space.shape == (84, 84, 4)
    single = crl.env_creator(EnvContext({"obs_type": "grayscale", "obs_size": [42, 42]}, worker_index=1))
    assert single.observation_space.shape == (42, 42)


def test_example_rejects_a_bad_env_config_before_starting_ray():
    run = subprocess.run(
        [sys.executable, str(EXAMPLE), "--env-config", '{"obs_type": "nope"}', "--iterations", "1"],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "RAY_ADDRESS": "127.0.0.1:1"},
    )
    assert run.returncode != 0
    assert run.stderr.strip().splitlines()[-1].startswith("error: invalid value nope for option `obs_type`")


@pytest.mark.parametrize(
    "flags, message",
    [
        (["--steps", "0"], "--steps must be >= 1, got 0"),
        (["--eval-episodes", "-1"], "--eval-episodes must be >= 0, got -1"),
        (["--eval-only", "--eval-episodes", "3"], "--eval-only needs --restore DIR and --eval-episodes N >= 1"),
        (["--eval-seed", "-5"], "--eval-seed must be in 0..2**63, got -5"),
        (["--export", "/no/such/folder/p.onnx"], "--export '/no/such/folder/p.onnx': '/no/such/folder' does not exist"),
        (["--sample-timeout", "0"], "--sample-timeout must be > 0, got 0.0"),
        (["--clip", "0"], "--clip must be a number > 0, got 0.0"),
        (["--clip", "nan"], "--clip must be a number > 0, got nan"),
        (["--kl-coeff", "-0.1"], "--kl-coeff must be a number >= 0, got -0.1"),
        (["--kl-coeff", "inf"], "--kl-coeff must be a number >= 0, got inf"),
        (["--lr-floor", "1"], "--lr-floor must be in [0, 1), got 1.0"),
        (["--lr-floor", "-0.5"], "--lr-floor must be in [0, 1), got -0.5"),
        (["--preset", "fast", "--env-runners", "3"], "--preset fast: its 128 games do not split over 3 runners evenly"),
        (["--export", "/"], "--export '/' is a folder: give the ONNX file to write"),
        (["--adam-eps", "0"], "--adam-eps must be a number in (0, 1), got 0.0"),
        (["--adam-eps", "nan"], "--adam-eps must be a number in (0, 1), got nan"),
        (["--adam-eps", "1e-5", "--no-norm-reward"], "--adam-eps is set in the reward-scaling learner"),
        (["--init", "xavier"], "argument --init: invalid choice: 'xavier'"),
        (["--obs-filter", "none"], "argument --obs-filter: invalid choice: 'none'"),
    ],
)
def test_example_rejects_bad_schedule_and_evaluation_flags(flags, message):
    run = subprocess.run(
        [sys.executable, str(EXAMPLE), *flags],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "RAY_ADDRESS": "127.0.0.1:1"},
    )
    assert run.returncode == 2 and message in run.stderr, run.stderr


def test_example_preset_is_the_trainers_preset_in_rllibs_terms():
    """`--preset fast` reads chopperscape.learn.recipe.PRESETS (one declaration), with the recipe's clip, no KL
    penalty (the recipe has none) and its learning-rate floor; a flag given beside it wins. Without a preset the
    example keeps RLlib's clip and KL penalty."""
    spec = importlib.util.spec_from_file_location("rllib_ppo_example", EXAMPLE)
    assert spec is not None and spec.loader is not None
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    from chopperscape.learn.recipe import LR_FLOOR, PRESETS, Recipe

    fast = PRESETS["fast"]
    a = example.parse_args(["--preset", "fast", "--env-runners", "2", "--lr", "5e-4", "--env-config", '{"lives": 2}'])
    batch = fast["num_envs"] * fast["num_steps"]
    assert a.envs_per_runner * 2 == fast["num_envs"] and a.train_batch_size == batch
    assert a.minibatch_size == batch // fast["num_minibatches"] and a.epochs == fast["update_epochs"]
    assert (a.gamma, a.lambda_, a.steps) == (fast["gamma"], fast["gae_lambda"], fast["total_steps"])
    assert a.entropy == Recipe().ent_coef and a.hidden == [Recipe().hidden] * 2
    assert (a.clip, a.kl_coeff, a.lr_floor) == (Recipe().clip_coef, 0.0, LR_FLOOR)
    assert a.lr == 5e-4  # the flag, not the preset's 1e-3
    assert example.parse_args(["--preset", "fast", "--kl-coeff", "0.2"]).kl_coeff == 0.2
    assert a.env_config == {"obs_type": "features", **fast["env_options"], "lives": 2}
    plain = example.parse_args([])
    assert (plain.envs_per_runner, plain.train_batch_size, plain.lr, plain.steps) == (16, 8192, 3e-4, None)
    assert (plain.clip, plain.kl_coeff) == (0.3, 0.2)  # RLlib's own
    assert (a.init, plain.init) == ("orthogonal", "torch")  # the recipe's initialisation; RLlib's own


def test_orthogonal_init_gives_rllibs_ppo_module_the_recipes_gains_by_head():
    """`--init orthogonal` re-initialises RLlib's own PPO module (its layer names are what the gains are chosen by):
    orthogonal rows of norm √2 in the encoders, 0.01 in the policy head and 1 in the value head, zero biases, the
    same weights for the same torch seed."""
    import gymnasium as gym
    import torch
    from ray.rllib.algorithms.ppo.ppo_catalog import PPOCatalog
    from ray.rllib.algorithms.ppo.torch.default_ppo_torch_rl_module import DefaultPPOTorchRLModule
    from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig

    from chopperscape.integrations.rllib import weights

    def module():
        return DefaultPPOTorchRLModule(
            observation_space=gym.spaces.Box(-1, 1, (46,), np.float32),
            action_space=gym.spaces.Discrete(5),
            model_config=DefaultModelConfig(fcnet_hiddens=[16, 16], vf_share_layers=False),
            catalog_class=PPOCatalog,
        )

    torch.manual_seed(3)
    m = module()
    assert weights.orthogonal(m) == 6
    layers = {n: x for n, x in m.named_modules() if isinstance(x, torch.nn.Linear)}
    assert {"pi.net.mlp.0", "vf.net.mlp.0"} <= set(layers)
    for name, layer in layers.items():
        g = {"pi": 0.01, "vf": 1.0}.get(name.split(".")[0], 2**0.5)
        w = layer.weight.detach().double()
        small = w @ w.T if w.shape[0] <= w.shape[1] else w.T @ w
        np.testing.assert_allclose(small.numpy(), g * g * np.eye(small.shape[0]), atol=1e-5, err_msg=name)
        assert not layer.bias.detach().any(), name
    torch.manual_seed(3)
    again = module()
    weights.orthogonal(again)
    for (n, x), (_, y) in zip(m.state_dict().items(), again.state_dict().items(), strict=True):
        assert torch.equal(x, y), n
    with pytest.raises(ValueError, match="init must be one of torch, orthogonal, got 'xavier'"):
        weights.initialise(None, "xavier")


def test_example_config_carries_the_presets_clip_kl_and_learning_rate_schedule():
    """What `--preset fast` sets reaches RLlib's PPOConfig: the clip, the KL penalty off, and the recipe's schedule
    (the rate falling to LR_FLOOR of itself at (1 - LR_FLOOR) x --steps, then held); `--lr-floor 0` is the old
    decay to 0 at --steps, and RLlib's own clip and KL penalty stay without a preset."""
    spec = importlib.util.spec_from_file_location("rllib_ppo_example", EXAMPLE)
    assert spec is not None and spec.loader is not None
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    from chopperscape.learn.recipe import LR_FLOOR, PRESETS

    fast = example.build_config(example.parse_args(["--preset", "fast"]))
    steps, lr = PRESETS["fast"]["total_steps"], PRESETS["fast"]["learning_rate"]
    assert (fast.clip_param, fast.use_kl_loss, fast.kl_coeff) == (0.2, False, 0.0)
    assert fast.lr == [[0, lr], [round((1 - LR_FLOOR) * steps), LR_FLOOR * lr]]
    old = example.build_config(example.parse_args(["--steps", "5000000", "--lr-floor", "0"]))
    assert old.lr == [[0, 3e-4], [5_000_000, 0.0]]
    assert (old.clip_param, old.use_kl_loss, old.kl_coeff) == (0.3, True, 0.2)
    assert example.build_config(example.parse_args([])).lr == 3e-4  # no budget, no schedule
    # Adam's epsilon reaches the learner's settings: torch's default (RLlib's own) unless --adam-eps gives one.
    assert example.build_config(example.parse_args([])).learner_config_dict["adam_eps"] is None
    assert example.build_config(example.parse_args(["--adam-eps", "1e-5"])).learner_config_dict["adam_eps"] == 1e-5


@pytest.mark.parametrize(
    "config, message",
    [
        ({"num_envs": 2, "obs_type": "nope"}, "obs_type"),
        ({"num_envs": 2, "no_such_option": 1}, "no_such_option"),
        ({"no_such_option": 1}, "no_such_option"),
        ({"num_envs": 2, "autoreset_mode": "same_step"}, "autoreset_mode"),
        ({"num_envs": 2, "copy": False}, "copy"),
    ],
)
def test_creator_rejects_bad_env_config_naming_the_option(config, message):
    with pytest.raises(ValueError, match=message):
        crl.env_creator(config)


def test_runner_threads_follow_the_cpus_ray_gave_the_runner(monkeypatch):
    monkeypatch.setattr(os, "sched_getaffinity", lambda _: set(range(8)), raising=False)
    monkeypatch.setenv("OMP_NUM_THREADS", "2")
    assert crl.env_creator({**FEATURES, "num_envs": 512}).unwrapped.num_threads == 2
    monkeypatch.delenv("OMP_NUM_THREADS")
    assert crl.env_creator({**FEATURES, "num_envs": 512}).unwrapped.num_threads == 8
    assert crl.env_creator({**FEATURES, "num_envs": 512, "num_threads": 3}).unwrapped.num_threads == 3


# Each runner built in this one process registers RLlib's env id again (Gymnasium warns about it).
reregistering = pytest.mark.filterwarnings("ignore:.*Overriding environment rllib-single-agent-env-v0")


@reregistering
@pytest.mark.parametrize("mode", ["vector_entry_point", "sync"])
def test_rllib_env_runners_seed_every_sub_env_differently(mode):
    """RLlib's own runners (built here in-process, as Ray builds them remotely): runner w resets with seed + w,
    which would give runner 1's env 1 and runner 2's env 0 the same game; here every seed differs."""
    config = (
        PPOConfig()
        .environment(crl.ENV_NAME, env_config=FEATURES)
        .env_runners(num_env_runners=3, num_envs_per_env_runner=4, gym_env_vectorize_mode=mode)
        .debugging(seed=11)
    )
    seeds = []
    for w in (1, 2, 3):
        runner = SingleAgentEnvRunner(config=config, worker_index=w, num_workers=3)
        episodes = runner.sample(num_timesteps=8, random_actions=True)
        assert sum(e.env_steps() for e in episodes) == 8
        if mode == "vector_entry_point":
            assert isinstance(runner.env.unwrapped, chopperscape.VectorEnv)
        seeds += crl.runner_seeds(runner)
        runner.stop()
    raw = [11 + w + i for w in (1, 2, 3) for i in range(4)]
    assert len(set(raw)) < len(raw)  # what RLlib and Gymnasium alone would give
    if mode == "vector_entry_point":
        assert seeds == [(11 + w) * K + i for w in (1, 2, 3) for i in range(4)]
    else:
        assert seeds == [(11 + w + i) * K + w for w in (1, 2, 3) for i in range(4)]
    assert len(set(seeds)) == 12


@reregistering
def test_float_pixels_feed_rllibs_default_cnn_with_grayscale_frames():
    config = (
        PPOConfig()
        .environment(crl.ENV_NAME, env_config={"obs_type": "grayscale", "obs_size": [84, 84]})
        .env_runners(
            num_env_runners=0,
            num_envs_per_env_runner=2,
            gym_env_vectorize_mode="vector_entry_point",
            env_to_module_connector=lambda env, spaces, device: crl.FloatPixels(),
        )
    )
    runner = SingleAgentEnvRunner(config=config, worker_index=0, num_workers=0)
    episodes = runner.sample(num_timesteps=4)
    assert sum(e.env_steps() for e in episodes) == 4
    space = crl.FloatPixels().recompute_output_observation_space(runner.env.single_observation_space, None)
    assert space.shape == (84, 84, 1) and space.dtype == np.float32
    frame = runner.env.unwrapped.reset(seed=1)[0][0]
    out = crl.FloatPixels().preprocess(frame, None)
    assert out.shape == (84, 84, 1) and out.dtype == np.float32
    np.testing.assert_allclose(out[..., 0], frame / 255.0, rtol=1e-6)
    runner.stop()


@reregistering
def test_return_scaling_runs_the_discounted_return_over_whole_episodes_across_batches():
    """The learner's ReturnScaling carries each unfinished episode's discounted return into its next chunk (as
    `NormalizeReward` does over a whole episode), through RLlib's own learner pipeline (which renames the chunks and
    appends a bootstrap step that must not count): after each batch its carry is the reference return of every
    live episode, and its statistics counted every real step once."""
    config = (
        PPOConfig()
        .environment(crl.ENV_NAME, env_config={"obs_type": "features", "frame_skip": 4})
        .env_runners(num_env_runners=0, num_envs_per_env_runner=4, gym_env_vectorize_mode="vector_entry_point")
        .training(train_batch_size_per_learner=64, minibatch_size=32, num_epochs=1, gamma=0.9)
        .learners(learner_class=crl.ReturnScaledPPOLearner)
        .debugging(seed=3)
    )
    runner = SingleAgentEnvRunner(config=config, worker_index=0, num_workers=0)
    learner = config.build_learner(env=runner.env)
    scaling = [p for p in learner._learner_connector.connectors if isinstance(p, crl.ReturnScaling)]
    assert len(scaling) == 1
    reference: dict[str, float] = {}
    steps = 0
    for _ in range(3):
        episodes = runner.sample(num_timesteps=64)
        live = {}
        for e in episodes:
            ret = reference.get(e.id_, 0.0)
            for r in e.get_rewards():
                ret = ret * 0.9 + float(r)
            steps += len(e)
            if not e.is_terminated:
                live[e.id_] = ret
        reference = live
        learner.update(episodes=episodes)
        assert scaling[0].carry.keys() == reference.keys()
        for i, ret in reference.items():
            assert scaling[0].carry[i] == pytest.approx(ret, rel=1e-9)
        assert scaling[0].rms.count == pytest.approx(steps + 1e-4)
    assert max(reference.values()) > 38  # three chunks of 16 decisions: near 4 / (1 - 0.9) = 40, not one chunk's 33
    runner.stop()


# --- a real Ray cluster on loopback ------------------------------------------------------------------------------


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _processes_mentioning(text: str) -> list[int]:
    """PIDs whose command line contains `text` (the cluster's temp dir names only its own processes)."""
    pids = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                cmdline = Path(f"/proc/{entry}/cmdline").read_bytes()
            except OSError:
                continue
            if text.encode() in cmdline:
                pids.append(int(entry))
    return pids


@pytest.fixture(scope="module")
def ray_cluster():
    """`ray start --head --block` on 127.0.0.1 with ports it picks, in its own temp dir, session and process group,
    with its own auth token; stopped by signalling that group and the processes naming its temp dir, never by a
    bare `ray stop` (which stops every Ray of this user on the machine)."""
    ray_cli = Path(sys.executable).parent / "ray"
    if not ray_cli.exists():
        pytest.skip(f"the `ray` command is not installed beside {sys.executable}")
    # Short: Ray's Unix socket paths under the temp dir must stay below 108 bytes.
    temp = tempfile.mkdtemp(prefix="cs-ray-", dir="/tmp")
    env = {
        **os.environ,
        "RAY_TMPDIR": temp,
        "RAY_AUTH_MODE": "token",
        "RAY_AUTH_TOKEN": secrets.token_hex(32),
        "RAY_GRACEFUL_SHUTDOWN_DRAIN_TIMEOUT_S": "0",
        "RAY_USAGE_STATS_ENABLED": "0",
    }
    port = _free_port()
    args = [
        str(ray_cli),
        "start",
        "--head",
        "--block",
        "--node-ip-address=127.0.0.1",
        f"--port={port}",
        f"--temp-dir={temp}",
        "--include-dashboard=false",
        f"--dashboard-port={_free_port()}",
        "--num-cpus=2",
        f"--object-store-memory={256 * 2**20}",
        "--disable-usage-stats",
        f"--node-manager-port={_free_port()}",
        f"--object-manager-port={_free_port()}",
        f"--dashboard-agent-listen-port={_free_port()}",
        f"--dashboard-agent-grpc-port={_free_port()}",
        f"--runtime-env-agent-port={_free_port()}",
        f"--metrics-export-port={_free_port()}",
    ]
    log_path = Path(temp) / "ray-start.log"
    with open(log_path, "w") as log:
        head = subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT, env=env, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while "block forever" not in log_path.read_text():
            if head.poll() is not None or time.monotonic() > deadline:
                pytest.fail(f"ray start --head did not come up:\n{log_path.read_text()[-3000:]}")
            time.sleep(0.5)
        yield {"address": f"127.0.0.1:{port}", "env": env, "temp": temp, "head_pid": head.pid}
    finally:
        _stop_cluster(head, temp)


def _stop_cluster(head: subprocess.Popen, temp: str) -> None:
    if head.poll() is None:
        head.send_signal(signal.SIGTERM)  # `ray start --block` stops the processes it started
        try:
            head.wait(timeout=30)
        except subprocess.TimeoutExpired:
            pass
    try:
        os.killpg(head.pid, signal.SIGKILL)  # anything of its process group still alive
    except ProcessLookupError:
        pass
    head.wait()
    for pid in _processes_mentioning(temp):  # workers that left the group
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    time.sleep(0.5)
    left = _processes_mentioning(temp)
    shutil.rmtree(temp, ignore_errors=True)
    assert not left, f"Ray processes of the test cluster still running: {left}"


def _train(cluster, out: Path, name: str, *extra: str) -> tuple[dict, list[dict]]:
    csv_path, summary_path = out / f"{name}.csv", out / f"{name}.json"
    cmd = [
        sys.executable,
        str(EXAMPLE),
        "--address",
        cluster["address"],
        "--env-runners",
        "2",
        "--envs-per-runner",
        "4",
        "--train-batch-size",
        "400",
        "--minibatch-size",
        "100",
        "--epochs",
        "1",
        "--hidden",
        "16",
        "--seed",
        "3",
        "--env-config",
        '{"max_fuel": 40}',
        "--minutes",
        "5",
        "--csv",
        str(csv_path),
        "--summary",
        str(summary_path),
        *extra,
    ]
    run = subprocess.run(cmd, check=False, env=cluster["env"], capture_output=True, text=True, timeout=420)
    assert run.returncode == 0, f"{' '.join(cmd)} failed:\n{run.stdout[-3000:]}\n{run.stderr[-6000:]}"
    with open(csv_path, newline="") as f:
        reader = csv.DictReader(f)
        assert reader.fieldnames == list(progress.RETURNS)
        rows = list(reader)
    return json.loads(summary_path.read_text()), rows


def test_ppo_on_a_local_cluster_with_two_runners_checkpoints_and_restores(ray_cluster, tmp_path):
    first_eval = tmp_path / "first.eval.json"
    summary, rows = _train(
        ray_cluster,
        tmp_path,
        "first",
        "--iterations",
        "2",
        "--init",
        "orthogonal",
        "--adam-eps",
        "1e-5",
        "--checkpoint",
        str(tmp_path / "ck"),
        "--eval-episodes",
        "3",
        "--eval-seed",
        "77",
        "--eval-out",
        str(first_eval),
        "--export",
        str(tmp_path / "policy.onnx"),
    )
    assert len(rows) == 2 == summary["iterations"]
    # One hidden layer: an encoder layer each for the actor and the critic, and the two heads.
    assert summary["initialised_layers"] == 4 and summary["settings"]["init"] == "orthogonal"
    assert summary["settings"]["adam_eps"] == 1e-5
    assert summary["settings"]["obs_filter"] == "synced"  # the exact merge of the two runners' statistics
    steps = [int(r["env_steps"]) for r in rows]
    assert steps[0] >= 400 and steps[1] >= steps[0] + 400 and steps[1] == summary["env_steps"]
    # Both runners sampled, each its own process, none of them the driver.
    per_runner = summary["steps_per_runner"]
    assert sorted(per_runner) == ["1", "2"] and all(n > 0 for n in per_runner.values())
    assert sum(per_runner.values()) == summary["env_steps"]
    assert sorted(summary["episodes_per_runner"]) == ["1", "2"]  # max_fuel 40: episodes of 40 steps
    pids = summary["pids_per_runner"]
    assert len({pids["1"], pids["2"], summary["driver_pid"]}) == 3
    assert float(rows[-1]["mean_length"]) == 40.0 and float(rows[-1]["mean_return"]) == 40.0
    # Native batches, seeded (3 + w) * K + i: eight distinct games.
    assert summary["seeds_per_runner"] == {str(w): [(3 + w) * K + i for i in range(4)] for w in (1, 2)}

    restored, rows2 = _train(
        ray_cluster, tmp_path, "second", "--iterations", "1", "--python-envs", "--restore", str(tmp_path / "ck")
    )
    assert restored["restored_weights_sha256"] == summary["weights_sha256"]
    assert restored["initialised_layers"] == 0  # a restore keeps its weights
    assert restored["restored_env_steps"] == summary["env_steps"]
    assert int(rows2[0]["env_steps"]) >= summary["env_steps"] + 400  # the counters continue
    assert sum(restored["steps_per_runner"].values()) == restored["env_steps"] - summary["env_steps"]
    assert restored["weights_sha256"] != summary["weights_sha256"]  # and training goes on from there
    seeds = [s for w in ("1", "2") for s in restored["seeds_per_runner"][w]]
    assert len(set(seeds)) == 8 and restored["seeds_per_runner"]["1"][0] == (3 + 1) * K + 1

    # --eval-only: the checkpoint, restored, plays the held-out episodes exactly as the run that wrote it did
    # (the same weights and the same frozen observation statistics).
    evaluated = json.loads(first_eval.read_text())
    assert evaluated["episodes"] == 3 and evaluated["seed"] == 77 and evaluated["greedy"] is True
    assert summary["evaluation"]["mean_return"] == evaluated["mean_return"]
    again = tmp_path / "again.eval.json"
    run = subprocess.run(
        [
            sys.executable,
            str(EXAMPLE),
            "--address",
            ray_cluster["address"],
            "--env-runners",
            "1",
            "--envs-per-runner",
            "4",
            "--hidden",
            "16",
            "--env-config",
            '{"max_fuel": 40}',
            "--restore",
            str(tmp_path / "ck"),
            "--eval-only",
            "--eval-episodes",
            "3",
            "--eval-seed",
            "77",
            "--eval-out",
            str(again),
        ],
        check=False,
        env=ray_cluster["env"],
        capture_output=True,
        text=True,
        timeout=420,
    )
    assert run.returncode == 0, run.stderr[-4000:]
    assert json.loads(again.read_text()) == evaluated

    # --export: a policy file the bench reads (with both runners' seed ranges), playing those episodes as the run did.
    assert summary["export"]["checked"] is True and summary["export"]["max_abs_diff"] <= 1e-5
    import onnxruntime

    from chopperscape.bench import evaluate as bench_evaluate
    from chopperscape.learn import episodes

    loaded = bench_evaluate.load(str(tmp_path / "policy.onnx"), "sticky-v0")
    assert json.loads(loaded.info["recipe"]["train_seeds"]) == [[(3 + w) * K, 4] for w in (1, 2)]
    assert json.loads(loaded.info["recipe"]["env_options"]) == {"max_fuel": 40}
    assert loaded.info["recipe"]["source_sha256"] == summary["weights_sha256"]
    session = onnxruntime.InferenceSession(str(tmp_path / "policy.onnx"), providers=["CPUExecutionProvider"])
    played = episodes.play_episodes(
        lambda obs, _envs: session.run(None, {"obs": obs})[0].argmax(-1),
        3,
        77,
        {"obs_type": "features", "max_fuel": 40},
    )
    assert episodes.summary(played)["mean_return"] == evaluated["mean_return"]


def test_the_bench_rows_rllib_flags_are_the_fast_preset_on_one_runner(tmp_path):
    """`bench row rllib-ppo` gives the trainer module (`python -m chopperscape.integrations.rllib.ppo`, which takes
    no --preset) explicit flags: the same settings as the example's `--preset fast --env-runners 1`; the module's
    learning-rate floor is the recipe's."""
    from chopperscape.bench import rows
    from chopperscape.integrations.rllib import flags
    from chopperscape.learn.recipe import LR_FLOOR

    assert flags.LR_FLOOR == LR_FLOOR
    spec = importlib.util.spec_from_file_location("rllib_ppo_example", EXAMPLE)
    assert spec is not None and spec.loader is not None
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    command = rows.train_command(rows.ROWS["rllib-ppo"], "full-v0", 3, 3_000_000, tmp_path, "py", "rpy")
    assert command[:3] == ["rpy", "-m", "chopperscape.integrations.rllib.ppo"]
    ours = vars(flags.parse_args(command[3:]))
    theirs = vars(example.parse_args(["--preset", "fast", "--env-runners", "1", "--seed", "3", "--steps", "3000000"]))
    theirs["env_config"]["mode"] = "full-v0"
    for key in ("csv", "summary", "export", "preset", "preset_env_options"):
        ours.pop(key, None), theirs.pop(key, None)
    assert ours == theirs
    with pytest.raises(SystemExit):
        flags.parse_args(["--preset", "fast"])  # the package's trainer has no presets


def test_bench_row_trains_an_rllib_seed_from_the_recipes_initialisation_and_evaluates_it(tmp_path):
    """`bench row rllib-ppo` at one iteration: the run folder and the results folder are made, the trainer starts
    from the recipe's orthogonal weights (6 layers), and the results file records the runner's seed range and the
    `--init` its trainer was given."""
    from chopperscape.bench import results

    runs, out = tmp_path / "runs", tmp_path / "results" / "new"
    command = [sys.executable, "-m", "chopperscape.bench", "row", "rllib-ppo", "--mode", "full-v0", "--seeds", "2"]
    command += ["--runs", str(runs), "--results", str(out), "--steps", "16384", "--rllib-python", sys.executable]
    env = {**os.environ, "RAY_worker_niceness": "0"}
    done = subprocess.run(command, capture_output=True, text=True, timeout=900, cwd=ROOT, env=env)
    assert done.returncode == 0, done.stderr + (runs / "seed-2.log").read_text()
    summary = json.loads((runs / "seed-2" / "summary.json").read_text())
    assert summary["initialised_layers"] == 6 and summary["settings"]["init"] == "orthogonal"
    assert summary["settings"]["adam_eps"] is None  # the row keeps RLlib's own Adam
    assert summary["settings"]["obs_filter"] == "synced"
    doc = results.load(out / "full-v0.rllib-ppo.seed2.json")
    assert doc["training"]["train_seeds"] == [[3 * 2**20, 128]] and doc["training"]["settings"]["init"] == "orthogonal"
