#!/usr/bin/env python3
"""PPO on ChopperScape-v0 with Ray RLlib (new API stack), on this machine or on a Ray cluster.

    python python/examples/rllib_ppo.py --minutes 10                    # a local Ray
    ray start --head ...; python python/examples/rllib_ppo.py --address auto ...  # join a running cluster

Each env runner is a separate process (a Ray actor) that steps `--envs-per-runner` games: by default one native
`chopperscape.VectorEnv` (one Rust call a batch), or with `--python-envs` as many Python envs in RLlib's
`SyncVectorEnv`. Every iteration appends a row to `--csv`, with the columns of the single-machine recipe:

    env_steps,wall_s,episodes,mean_return,std_return,mean_length

`env_steps`: env steps sampled so far; `wall_s`: seconds since training started; `episodes`: episodes finished so
far; the others over the last 100 finished episodes (rows start once an episode has finished, as in the recipe).
`--checkpoint DIR` saves the algorithm at the end; `--restore DIR` starts from such a checkpoint; `--summary FILE`
writes a JSON summary (steps, seeds, PIDs and nodes per runner, a digest of the policy's weights). See docs/rllib.md.
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import hashlib
import json
import math
import os
import sys
import time
from pathlib import Path
from typing import Any

from chopperscape.learn.recipe import DEFAULT_STEPS, LR_FLOOR, PRESETS, Recipe

#: Episodes the mean and std of each row are taken over.
WINDOW = 100
_FINISHED = "_chopperscape_finished"
_SAMPLED = "_chopperscape_sampled"


#: The example's own settings where neither a flag nor `--preset` gives one.
DEFAULTS: dict[str, Any] = {
    "envs_per_runner": 16,
    "train_batch_size": 8192,
    "minibatch_size": 1024,
    "epochs": 4,
    "lr": 3e-4,
    "gamma": 0.995,
    "lambda_": 0.95,
    "entropy": 0.01,
    "hidden": "128,128",
    # RLlib's own: PPO's clip 0.3 and its adaptive KL penalty, starting at 0.2.
    "clip": 0.3,
    "kl_coeff": 0.2,
}


def preset_settings(name: str, env_runners: int) -> dict[str, Any]:
    """The settings of `chopperscape.learn.train --preset NAME` (features) as this example's flags: its games split
    over `env_runners` runners (the driver's, with 0), one batch of games x steps, its minibatches, epochs, lr,
    gamma, lambda, entropy, clip, two hidden layers of its width, its step budget and env options, and no KL
    penalty (the recipe has none). `ValueError` if the games do not split evenly."""
    preset = PRESETS[name]
    r = Recipe(**{k: v for k, v in preset.items() if k != "total_steps"})
    runners = max(env_runners, 1)
    if r.num_envs % runners:
        raise ValueError(f"--preset {name}: its {r.num_envs} games do not split over {runners} runners evenly")
    batch = r.num_envs * r.num_steps
    return {
        "envs_per_runner": r.num_envs // runners,
        "train_batch_size": batch,
        "minibatch_size": batch // r.num_minibatches,
        "epochs": r.update_epochs,
        "lr": r.learning_rate,
        "gamma": r.gamma,
        "lambda_": r.gae_lambda,
        "entropy": r.ent_coef,
        "clip": r.clip_coef,
        "kl_coeff": 0.0,
        "hidden": f"{r.hidden},{r.hidden}",
        "steps": preset.get("total_steps", DEFAULT_STEPS),
        "preset_env_options": dict(r.env_options),
    }


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--env-runners", type=int, default=2, help="env runner processes (0: sample in this process)")
    p.add_argument(
        "--envs-per-runner", type=int, default=None, help="games each runner steps as one batch (default 16)"
    )
    p.add_argument("--cpus-per-runner", type=float, default=1, help="CPUs Ray reserves for each runner")
    p.add_argument(
        "--sample-timeout",
        type=float,
        default=600.0,
        help="seconds an iteration waits for its runners' samples (RLlib's default, 60, is too short for a "
        "large batch on busy cores; default 600)",
    )
    p.add_argument("--address", default=None, help="Ray cluster to join ('auto', or host:port); default: a local Ray")
    p.add_argument(
        "--minutes",
        type=float,
        default=None,
        help="training time (stops after the iteration past it; default 30 unless --steps or --iterations is given)",
    )
    p.add_argument("--iterations", type=int, default=None, help="stop after this many iterations (also)")
    p.add_argument(
        "--steps",
        type=int,
        default=None,
        help="stop after the iteration that reaches this many env steps; the learning rate then falls linearly "
        "over them to --lr-floor of itself, as the recipe's (--no-anneal-lr keeps it constant)",
    )
    p.add_argument(
        "--lr-floor",
        type=float,
        default=LR_FLOOR,
        help=f"the fraction of the learning rate the decay stops at, at (1 - floor) x --steps (default the recipe's "
        f"{LR_FLOOR}; 0 falls to 0 at --steps, the schedule of this example's runs before the bench's rows)",
    )
    p.add_argument(
        "--no-anneal-lr", dest="anneal_lr", action="store_false", help="constant learning rate even with --steps"
    )
    p.add_argument(
        "--csv",
        default="runs/rllib-ppo/progress.csv",
        help="learning curve, one row per iteration (overwritten; default runs/rllib-ppo/progress.csv)",
    )
    mode = p.add_mutually_exclusive_group()
    mode.add_argument(
        "--native", dest="native", action="store_true", default=True, help="one native VectorEnv per runner (default)"
    )
    mode.add_argument(
        "--python-envs", dest="native", action="store_false", help="Python sub-envs in RLlib's SyncVectorEnv instead"
    )
    p.add_argument("--obs-type", default="features", help="env option obs_type (default: features)")
    p.add_argument("--env-config", default="{}", help="more env options as JSON, e.g. '{\"alien_prob\": 0.1}'")
    p.add_argument("--seed", type=int, default=0, help="RLlib seed (runner w, env i get distinct game seeds)")
    p.add_argument(
        "--preset",
        choices=sorted(k for k, v in PRESETS.items() if "obs_type" not in v),
        default=None,
        help="a features preset of chopperscape.learn.train in RLlib's terms (read from its one declaration, "
        "chopperscape.learn.recipe.PRESETS): its games (split over the runners), batch, minibatches, epochs, lr, "
        "gamma, lambda, entropy, clip, hidden width, frame skip and step budget, and no KL penalty; a flag given "
        "here wins",
    )
    p.add_argument("--train-batch-size", type=int, default=None, help="env steps per training iteration (8192)")
    p.add_argument("--minibatch-size", type=int, default=None, help="(default 1024)")
    p.add_argument("--epochs", type=int, default=None, help="passes over each train batch (default 4)")
    p.add_argument("--lr", type=float, default=None, help="(default 3e-4)")
    p.add_argument("--gamma", type=float, default=None, help="(default 0.995)")
    p.add_argument("--lambda", dest="lambda_", type=float, default=None, help="(default 0.95)")
    p.add_argument("--entropy", type=float, default=None, help="entropy bonus coefficient (default 0.01)")
    p.add_argument("--clip", type=float, default=None, help="PPO's clip of the probability ratio (default RLlib's 0.3)")
    p.add_argument(
        "--kl-coeff",
        type=float,
        default=None,
        help="initial weight of RLlib's adaptive KL penalty (default RLlib's 0.2; 0 turns the penalty off)",
    )
    p.add_argument(
        "--no-norm-reward",
        dest="norm_reward",
        action="store_false",
        help="do not scale rewards by the running std of the discounted return",
    )
    p.add_argument(
        "--hidden", default=None, help="hidden layer sizes of the policy and value networks (default 128,128)"
    )
    p.add_argument(
        "--torch-threads",
        type=int,
        default=1,
        help="torch threads of this process (the learner, and the sampler with 0 runners); runners get "
        "their CPUs' worth from Ray",
    )
    p.add_argument("--checkpoint", default=None, help="save the algorithm to this directory at the end")
    p.add_argument("--restore", default=None, help="start from a checkpoint saved by --checkpoint")
    p.add_argument("--summary", default=None, help="write a JSON summary to this file at the end")
    p.add_argument(
        "--export",
        default=None,
        metavar="FILE.onnx",
        help="write the trained policy as a ChopperScape policy file (the format of chopperscape.learn.export, with "
        "its training seeds) for `python -m chopperscape.bench evaluate`, the command line and the page",
    )
    p.add_argument(
        "--eval-episodes",
        type=int,
        default=0,
        help="after training, play this many episodes greedily on seeds --eval-seed, +1, ... (default 0: none), "
        "as `python -m chopperscape.learn.evaluate` does, and write its JSON to --eval-out",
    )
    p.add_argument("--eval-seed", type=int, default=1_000_000, help="first evaluation seed (default 1000000)")
    p.add_argument("--eval-out", default=None, help="evaluation JSON (default: printed)")
    p.add_argument(
        "--eval-only",
        action="store_true",
        help="no training: evaluate the checkpoint given by --restore (which is a pickle: only your own or trusted)",
    )
    args = p.parse_args(argv)
    settings = dict(DEFAULTS)
    if args.preset is not None:
        try:
            settings.update(preset_settings(args.preset, args.env_runners))
        except ValueError as e:
            p.error(str(e))
    for name, value in settings.items():
        if getattr(args, name, None) is None:
            setattr(args, name, value)
    if args.env_runners < 0:
        p.error(f"--env-runners must be >= 0, got {args.env_runners}")
    if args.envs_per_runner < 1:
        p.error(f"--envs-per-runner must be >= 1, got {args.envs_per_runner}")
    if not 0 <= args.lr_floor < 1:
        p.error(f"--lr-floor must be in [0, 1), got {args.lr_floor}")
    if not 0 < args.clip < math.inf:
        p.error(f"--clip must be a number > 0, got {args.clip}")
    if not 0 <= args.kl_coeff < math.inf:
        p.error(f"--kl-coeff must be a number >= 0, got {args.kl_coeff}")
    if not args.sample_timeout > 0:
        p.error(f"--sample-timeout must be > 0, got {args.sample_timeout}")
    if args.cpus_per_runner <= 0:
        p.error(f"--cpus-per-runner must be > 0, got {args.cpus_per_runner}")
    if args.minutes is None and args.steps is None and args.iterations is None:
        args.minutes = 30.0
    if args.minutes is not None and not args.minutes > 0:
        p.error(f"--minutes must be > 0, got {args.minutes}")
    if args.steps is not None and args.steps < 1:
        p.error(f"--steps must be >= 1, got {args.steps}")
    if args.torch_threads < 1:
        p.error(f"--torch-threads must be >= 1, got {args.torch_threads}")
    if args.eval_episodes < 0:
        p.error(f"--eval-episodes must be >= 0, got {args.eval_episodes}")
    if not 0 <= args.eval_seed < 2**63:
        p.error(f"--eval-seed must be in 0..2**63, got {args.eval_seed}")
    if args.eval_only and (args.restore is None or args.eval_episodes < 1):
        p.error("--eval-only needs --restore DIR and --eval-episodes N >= 1")
    if args.iterations is not None and args.iterations < 1:
        p.error(f"--iterations must be >= 1, got {args.iterations}")
    try:
        extra = json.loads(args.env_config)
    except json.JSONDecodeError as e:
        p.error(f"--env-config is not JSON ({e}): give an object such as '{{\"alien_prob\": 0.1}}'")
    if not isinstance(extra, dict):
        p.error("--env-config must be a JSON object such as '{\"alien_prob\": 0.1}'")
    args.env_config = {"obs_type": args.obs_type, **getattr(args, "preset_env_options", {}), **extra}
    try:
        args.hidden = [int(h) for h in args.hidden.split(",")]
    except ValueError:
        p.error(f"--hidden must be comma-separated integers such as 64,64, got {args.hidden!r}")
    if args.export is not None:
        from chopperscape.policyfile import check_out

        try:
            check_out(Path(args.export), force=True)
        except ValueError as e:
            p.error(str(e).replace("--out", "--export"))
    if args.restore is not None and not os.path.isdir(args.restore):
        p.error(f"--restore {args.restore!r} is not a directory (give one written by --checkpoint)")
    return args


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

    import chopperscape.integrations.rllib

    return (
        int(env_runner.worker_index or 0),
        int(env_runner.__dict__.get(_SAMPLED, 0)),
        chopperscape.integrations.rllib.runner_seeds(env_runner),
        os.getpid(),
        ray.get_runtime_context().get_node_id(),
    )


def build_config(args: argparse.Namespace):
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.connectors.env_to_module.mean_std_filter import MeanStdFilter
    from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig

    import chopperscape.integrations.rllib  # registers "ChopperScape-v0" with RLlib

    return (
        PPOConfig()
        .environment(chopperscape.integrations.rllib.ENV_NAME, env_config=args.env_config)
        .env_runners(
            num_env_runners=args.env_runners,
            num_envs_per_env_runner=args.envs_per_runner,
            num_cpus_per_env_runner=args.cpus_per_runner,
            sample_timeout_s=args.sample_timeout,
            gym_env_vectorize_mode="vector_entry_point" if args.native else "sync",
            # Features normalised by running mean and std (the filter's state is synced and checkpointed);
            # pixels as floats in [0, 1] with a channel axis, for RLlib's default CNN.
            env_to_module_connector=(
                (lambda env, spaces, device: MeanStdFilter())
                if args.env_config.get("obs_type") == "features"
                else (lambda env, spaces, device: chopperscape.integrations.rllib.FloatPixels())
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
        .learners(learner_class=chopperscape.integrations.rllib.ReturnScaledPPOLearner if args.norm_reward else None)
        .rl_module(model_config=DefaultModelConfig(fcnet_hiddens=args.hidden, vf_share_layers=False))
        .callbacks(on_episode_end=record_episode, on_sample_end=count_steps)
        .debugging(seed=args.seed)
    )


def evaluate(algo: Any, args: argparse.Namespace) -> dict[str, Any]:
    """Greedy episodes of the trained module on seeds `--eval-seed`, +1, ..., played and summarised by
    `chopperscape.learn.evaluate` (the same JSON as `python -m chopperscape.learn.evaluate`), with the
    observations normalised by the runners' filter statistics, frozen."""
    import numpy as np
    import torch

    import chopperscape
    from chopperscape.integrations.rllib import float_pixels, observation_filter
    from chopperscape.learn import episodes as chopper_episodes

    module = algo.get_module()
    probe = chopperscape.VectorEnv(1, **args.env_config)
    space = probe.single_observation_space
    probe.close()
    normalise = None
    if args.env_config.get("obs_type") == "features":
        normalise = observation_filter(algo, space)
        if normalise is None:
            raise SystemExit("error: no runner has the observation filter's statistics to evaluate with")

    def act(obs: np.ndarray, _envs: Any) -> np.ndarray:
        x = normalise(obs, update=False) if normalise is not None else float_pixels(obs, len(space.shape))
        with torch.no_grad():
            out = module.forward_inference({"obs": torch.as_tensor(np.asarray(x, dtype=np.float32))})
        return out["action_dist_inputs"].argmax(-1).cpu().numpy()

    options = {k: v for k, v in args.env_config.items() if k != "max_episode_steps"}
    limit = args.env_config.get("max_episode_steps", 10_000)
    results = chopper_episodes.play_episodes(act, args.eval_episodes, args.eval_seed, options, max_episode_steps=limit)
    out: dict[str, Any] = {"model": args.checkpoint or args.restore or "rllib", "seed": args.eval_seed, "greedy": True}
    out.update(chopper_episodes.summary(results))
    return out


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


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    import ray
    import torch

    # Ray limits its workers' threads to their CPUs, not the driver's: torch's default (all cores) oversubscribes
    # a machine whose cores the runners use (8x slower sampling with 0 runners on 2 busy cores).
    torch.set_num_threads(args.torch_threads)
    import chopperscape.integrations.rllib
    from chopperscape.learn import progress

    try:
        chopperscape.integrations.rllib.check_env_config(args.env_config)
    except ValueError as e:
        raise SystemExit(f"error: {e}") from None
    connect(args)
    algo = build_config(args).build_algo()
    summary: dict[str, Any] = {
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
    window: collections.deque = collections.deque(maxlen=WINDOW)
    episodes_per_runner: collections.Counter = collections.Counter()
    episodes = 0
    env_steps = 0
    iterations = 0
    start = time.monotonic()
    with progress.Writer(args.csv, progress.RETURNS) if not args.eval_only else contextlib.nullcontext() as out:
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
    if args.eval_episodes:
        report = evaluate(algo, args)
        summary["evaluation"] = {k: report[k] for k in ("episodes", "mean_return", "std_return", "causes")}
        text = json.dumps(report)
        if args.eval_out:
            with open(args.eval_out, "w") as f:
                f.write(text + "\n")
        print(text, flush=True)
    if args.export:
        from chopperscape.integrations.rllib import export_onnx, runner_seeds, seed_ranges

        seeds = [s for runner in group.foreach_env_runner(runner_seeds, local_env_runner=True) for s in runner]
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
