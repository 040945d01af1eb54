"""PPO on ChopperScape-v0 with Ray RLlib (new API stack), on this machine or on a Ray cluster: the trainer of the
bench's RLlib row and of `python/examples/rllib_ppo.py` (which adds `--preset` and `--eval-episodes`).

    python -m chopperscape.integrations.rllib.ppo --steps 3000000 --env-runners 1 --envs-per-runner 128 ... \
        --seed 0 --env-config '{"mode": "sticky-v0"}' --summary run/summary.json --export run/model.onnx

Each env runner is a separate process (a Ray actor) that steps `--envs-per-runner` games: by default one native
`chopperscape.VectorEnv` (one Rust call a batch), or with `--python-envs` as many Python envs in RLlib's
`SyncVectorEnv`. Every iteration appends a row to `--csv`, with the columns of the single-machine recipe:

    env_steps,wall_s,episodes,mean_return,std_return,mean_length

`env_steps`: env steps sampled so far; `wall_s`: seconds since training started; `episodes`: episodes finished so
far; the others over the last 100 finished episodes (rows start once an episode has finished, as in the recipe).
`--checkpoint DIR` saves the algorithm at the end; `--restore DIR` starts from such a checkpoint; `--summary FILE`
writes a JSON summary: steps, seeds, PIDs and nodes per runner, a digest of the policy's weights, the trainer's
full `settings` (every flag's value and the constants of its config) and `train_seeds`, the reset-seed ranges
`[[first, count], ...]` of every runner's games as RLlib seeded them (runner `w` of seed `s`: `(s + w) * 2**20 + i`).
See docs/rllib.md.
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import csv
import hashlib
import json
import math
import os
import sys
import time
from collections.abc import Callable
from typing import Any

from . import flags
from .weights import initialise

#: Episodes the mean and std of each row are taken over.
WINDOW = 100
#: The progress CSV's columns (`chopperscape.learn.progress.RETURNS`; this layer does not import learn).
COLUMNS = ("env_steps", "wall_s", "episodes", "mean_return", "std_return", "mean_length")
_FINISHED = "_chopperscape_finished"
_SAMPLED = "_chopperscape_sampled"
#: The config's settings that no flag changes (recorded in the summary's `settings` beside the flags').
CONSTANTS: dict[str, Any] = {
    "vf_loss_coeff": 0.5,
    "vf_clip_param": None,  # off (math.inf): rewards are scaled
    "grad_clip": 0.5,
    "vf_share_layers": False,
    "observation_filter": "features: --obs-filter's MeanStdFilter; pixels: FloatPixels",
}
#: The flags that are settings of the run (recorded), not where it writes.
SETTINGS = (
    "env_runners", "envs_per_runner", "cpus_per_runner", "native", "env_config", "seed", "train_batch_size",
    "minibatch_size", "epochs", "lr", "lr_floor", "anneal_lr", "steps", "minutes", "iterations", "gamma", "lambda_",
    "entropy", "clip", "kl_coeff", "norm_reward", "adam_eps", "hidden", "init", "obs_filter", "torch_threads",
    "sample_timeout", "restore",
)  # fmt: skip
#: An evaluation hook: `(algo, args) -> JSON report` (python/examples/rllib_ppo.py's plays greedy episodes).
Evaluate = Callable[[Any, argparse.Namespace], dict[str, Any]]


def settings(args: argparse.Namespace) -> dict[str, Any]:
    """The run's full settings: every setting flag's value, and :data:`CONSTANTS`."""
    import ray

    return {**{k: getattr(args, k, None) for k in SETTINGS}, **CONSTANTS, "ray": ray.__version__}


class _Curve:
    def __init__(self, path: str) -> None:
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        self.file = open(path, "w", newline="")
        self.csv = csv.writer(self.file)
        self.csv.writerow(COLUMNS)

    def row(self, values: dict[str, Any]) -> None:
        self.csv.writerow([values[c] for c in COLUMNS])
        self.file.flush()

    def __enter__(self) -> _Curve:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.file.close()


def record_episode(*, episode, prev_episode_chunks, env_runner, **_: Any) -> None:
    """RLlib callback (`on_episode_end`, in the env runner): keeps (runner, return, length) of each finished
    episode on the runner, for the driver to collect after each iteration."""
    chunks = [*prev_episode_chunks, episode]
    record = (
        int(env_runner.worker_index or 0),
        float(sum(c.get_return() for c in chunks)),
        int(sum(len(c) for c in chunks)),
    )
    env_runner.__dict__.setdefault(_FINISHED, []).append(record)


def count_steps(*, env_runner, samples, **_: Any) -> None:
    """RLlib callback (`on_sample_end`, in the env runner): counts the env steps this runner sampled (RLlib's
    `num_env_steps_sampled_lifetime` on a runner is an estimate of the whole group's)."""
    steps = sum(e.env_steps() for e in samples)
    env_runner.__dict__[_SAMPLED] = env_runner.__dict__.get(_SAMPLED, 0) + steps


def collect_episodes(env_runner: Any) -> list[tuple[int, float, int]]:
    """Takes the episodes `record_episode` kept on a runner (runs in the runner)."""
    return env_runner.__dict__.pop(_FINISHED, [])


def runner_report(env_runner: Any) -> tuple[int, int, list, int, str]:
    """(runner index, env steps it sampled, game seeds of its sub-envs, process id, Ray node id) of a runner."""
    import ray

    from . import runner_seeds

    return (
        int(env_runner.worker_index or 0),
        int(env_runner.__dict__.get(_SAMPLED, 0)),
        runner_seeds(env_runner),
        os.getpid(),
        ray.get_runtime_context().get_node_id(),
    )


def build_config(args: argparse.Namespace):
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.connectors.env_to_module.mean_std_filter import MeanStdFilter
    from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig

    from . import ENV_NAME, FloatPixels, ReturnScaledPPOLearner  # registers "ChopperScape-v0" with RLlib
    from .meanstd import SyncedMeanStdFilter

    observation_filter = SyncedMeanStdFilter if args.obs_filter == "synced" else MeanStdFilter

    return (
        PPOConfig()
        .environment(ENV_NAME, env_config=args.env_config)
        .env_runners(
            num_env_runners=args.env_runners,
            num_envs_per_env_runner=args.envs_per_runner,
            num_cpus_per_env_runner=args.cpus_per_runner,
            sample_timeout_s=args.sample_timeout,
            gym_env_vectorize_mode="vector_entry_point" if args.native else "sync",
            # Features normalised by running mean and std (the filter's state is synced and checkpointed);
            # pixels as floats in [0, 1] with a channel axis, for RLlib's default CNN.
            env_to_module_connector=(
                (lambda env, spaces, device: observation_filter())
                if args.env_config.get("obs_type") == "features"
                else (lambda env, spaces, device: FloatPixels())
            ),
        )
        .training(
            train_batch_size_per_learner=args.train_batch_size,
            minibatch_size=args.minibatch_size,
            num_epochs=args.epochs,
            # The recipe's schedule: linear decay to floor x lr at (1 - floor) x --steps, then held (RLlib
            # interpolates [[step, lr], ...] by env steps and keeps the last value past the last point).
            lr=(
                [[0, args.lr], [round((1 - args.lr_floor) * args.steps), args.lr_floor * args.lr]]
                if args.steps and args.anneal_lr
                else args.lr
            ),
            gamma=args.gamma,
            lambda_=args.lambda_,
            entropy_coeff=args.entropy,
            clip_param=args.clip,
            use_kl_loss=args.kl_coeff > 0,
            kl_coeff=args.kl_coeff,
            vf_loss_coeff=0.5,
            vf_clip_param=math.inf,  # rewards are scaled (below); RLlib's default clips the value loss at 10
            grad_clip=0.5,
        )
        .learners(
            learner_class=ReturnScaledPPOLearner if args.norm_reward else None,
            learner_config_dict={"adam_eps": args.adam_eps},
        )
        .rl_module(model_config=DefaultModelConfig(fcnet_hiddens=args.hidden, vf_share_layers=False))
        .callbacks(on_episode_end=record_episode, on_sample_end=count_steps)
        .debugging(seed=args.seed)
    )


def weights_digest(algo: Any) -> str:
    """SHA-256 of the learner's policy weights (names and values), to compare a checkpoint with its restore."""
    import numpy as np

    weights = algo.learner_group.get_weights()
    h = hashlib.sha256()
    for module_id in sorted(weights):
        for name in sorted(weights[module_id]):
            h.update(f"{module_id}/{name}".encode())
            h.update(np.ascontiguousarray(np.asarray(weights[module_id][name])).tobytes())
    return h.hexdigest()


def connect(args: argparse.Namespace) -> None:
    import ray

    if args.address is None:
        ray.init(logging_level="WARNING")
    else:
        ray.init(address=args.address, logging_level="WARNING")
    need = args.env_runners * args.cpus_per_runner
    have = ray.cluster_resources().get("CPU", 0)
    if need > have:
        raise SystemExit(
            f"error: {args.env_runners} env runners x {args.cpus_per_runner} CPUs need {need:g} CPUs, the Ray "
            f"cluster has {have:g}: lower --env-runners or --cpus-per-runner, or add nodes"
        )


def _train(algo: Any, args: argparse.Namespace, start: float) -> tuple[int, int, int, collections.Counter]:
    """Trains until the budget (`--minutes`, `--iterations`, `--steps`), a progress row per iteration once an episode
    has finished (the recipe's columns); returns the iterations, env steps, episodes and episodes per runner."""
    group = algo.env_runner_group
    window: collections.deque = collections.deque(maxlen=WINDOW)
    episodes_per_runner: collections.Counter = collections.Counter()
    episodes = 0
    env_steps = 0
    iterations = 0
    with _Curve(args.csv) if not args.eval_only else contextlib.nullcontext() as out:
        while not args.eval_only:
            result = algo.train()
            iterations += 1
            wall = time.monotonic() - start
            for runner_episodes in group.foreach_env_runner(collect_episodes, local_env_runner=True):
                for runner, ret, length in runner_episodes:
                    window.append((ret, length))
                    episodes_per_runner[runner] += 1
                    episodes += 1
            # An iteration whose runners returned no samples in time (RLlib warns "No samples returned") reports
            # no runner metrics: the count stays where it was.
            env_steps = int(result.get("env_runners", {}).get("num_env_steps_sampled_lifetime", env_steps))
            if window:  # like the recipe, rows start once an episode has finished
                returns = [r for r, _ in window]
                mean = sum(returns) / len(returns)
                std = math.sqrt(sum((r - mean) ** 2 for r in returns) / len(returns))
                length = sum(n for _, n in window) / len(window)
                assert out is not None
                out.row(
                    {
                        "env_steps": env_steps,
                        "wall_s": f"{wall:.2f}",
                        "episodes": episodes,
                        "mean_return": f"{mean:.3f}",
                        "std_return": f"{std:.3f}",
                        "mean_length": f"{length:.1f}",
                    }
                )
            else:
                mean = std = length = math.nan
            print(
                f"iter {iterations:4d}  steps {env_steps:9d}  episodes {episodes:6d}  "
                f"return {mean:9.1f} ± {std:7.1f}  length {length:8.1f}  {wall:7.1f}s",
                flush=True,
            )
            if (
                (args.minutes is not None and wall >= args.minutes * 60)
                or (args.iterations is not None and iterations >= args.iterations)
                or (args.steps is not None and env_steps >= args.steps)
            ):
                break
    return iterations, env_steps, episodes, episodes_per_runner


def main(
    argv: list[str] | None = None, args: argparse.Namespace | None = None, evaluate: Evaluate | None = None
) -> int:
    """Trains as the command line `argv` (or the parsed `args`) says; `evaluate` runs `--eval-episodes`."""
    args = flags.parse_args(argv) if args is None else args
    if args.eval_episodes and evaluate is None:
        raise SystemExit("error: --eval-episodes: this trainer has no evaluation; use python/examples/rllib_ppo.py")
    import ray
    import torch

    # Ray limits its workers' threads to their CPUs, not the driver's: torch's default (all cores) oversubscribes
    # a machine whose cores the runners use (8x slower sampling with 0 runners on 2 busy cores).
    torch.set_num_threads(args.torch_threads)
    from . import check_env_config, runner_seeds, seed_ranges

    try:
        check_env_config(args.env_config)
    except ValueError as e:
        raise SystemExit(f"error: {e}") from None
    connect(args)
    algo = build_config(args).build_algo()
    # A restore brings its own weights.
    initialised = 0 if args.restore else initialise(algo, args.init)
    summary: dict[str, Any] = {
        "initialised_layers": initialised,
        "native": args.native,
        "env_runners": args.env_runners,
        "envs_per_runner": args.envs_per_runner,
    }
    if args.restore:
        algo.restore_from_path(os.path.abspath(args.restore))
        summary["restored_weights_sha256"] = weights_digest(algo)
        summary["restored_env_steps"] = int(
            algo.metrics.peek(("env_runners", "num_env_steps_sampled_lifetime"), default=0)
        )
    group = algo.env_runner_group
    start = time.monotonic()
    iterations, env_steps, episodes, episodes_per_runner = _train(algo, args, start)
    reports = [r for r in group.foreach_env_runner(runner_report, local_env_runner=True) if r[2]]
    summary.update(
        iterations=iterations,
        env_steps=env_steps,
        wall_s=round(time.monotonic() - start, 2),
        episodes=episodes,
        episodes_per_runner={str(k): v for k, v in sorted(episodes_per_runner.items())},
        steps_per_runner={str(w): steps for w, steps, *_ in reports},
        seeds_per_runner={str(w): seeds for w, _, seeds, *_ in reports},
        pids_per_runner={str(w): pid for w, _, _, pid, _ in reports},
        nodes_per_runner={str(w): node for w, *_, node in reports},
        driver_pid=os.getpid(),
        weights_sha256=weights_digest(algo),
    )
    seeds = [s for runner in group.foreach_env_runner(runner_seeds, local_env_runner=True) for s in runner]
    summary["settings"] = settings(args)
    try:
        summary["train_seeds"] = [list(r) for r in seed_ranges(seeds)]
    except ValueError:
        summary["train_seeds"] = None  # an env reset without a seed (an --eval-only run has none)
    if args.eval_episodes:
        assert evaluate is not None
        report = evaluate(algo, args)
        summary["evaluation"] = {k: report[k] for k in ("episodes", "mean_return", "std_return", "causes")}
        text = json.dumps(report)
        if args.eval_out:
            with open(args.eval_out, "w") as f:
                f.write(text + "\n")
        print(text, flush=True)
    if args.export:
        from . import export_onnx

        try:
            summary["export"] = export_onnx(
                algo,
                args.env_config,
                args.export,
                train_seeds=seed_ranges(seeds),
                source_sha256=summary["weights_sha256"],
                force=True,
            )
        except (ValueError, OSError, RuntimeError) as e:
            raise SystemExit(f"error: --export {args.export!r}: {e}") from None
        print(json.dumps(summary["export"]), flush=True)
    if args.checkpoint:
        summary["checkpoint"] = algo.save_to_path(os.path.abspath(args.checkpoint))
    if args.summary:
        with open(args.summary, "w") as f:
            json.dump(summary, f, indent=1)
    algo.stop()
    ray.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
