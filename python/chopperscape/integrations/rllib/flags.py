"""The command line of the RLlib PPO trainer (:mod:`.ppo`): its flags, their checks, and a features recipe's
settings in RLlib's terms (:func:`recipe_settings`). `python/examples/rllib_ppo.py` adds `--preset` (the presets of
`chopperscape.learn.recipe`, which this layer does not import) through `parse_args(presets=...)`."""

from __future__ import annotations

import argparse
import json
import math
import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from .weights import INITS

#: `--obs-filter`'s choices: features normalised by `.meanstd.SyncedMeanStdFilter` or RLlib's own `MeanStdFilter`.
OBS_FILTERS = ("synced", "rllib")

#: The learning rate's floor of the recipe's schedule (`chopperscape.learn.recipe.LR_FLOOR`, tested equal).
LR_FLOOR = 0.05

#: The trainer's own settings where neither a flag nor `--preset` gives one.
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
    # RLlib's own: torch's default initialisation of its module.
    "init": "torch",
    # Not RLlib's own: its MeanStdFilter's merge across runners drifts (`.meanstd`); "rllib" keeps it.
    "obs_filter": "synced",
}


def recipe_settings(recipe: Any, steps: int, env_runners: int) -> dict[str, Any]:
    """The settings of a features recipe (:class:`chopperscape.learn.recipe.Recipe`, read by attribute) as this
    trainer's flags: its games split over `env_runners` runners (the driver's, with 0), one batch of games x steps,
    its minibatches, epochs, lr, gamma, lambda, entropy, clip, two hidden layers of its width, its orthogonal
    initialisation, the step budget `steps` and its env options, and no KL penalty (the recipe has none).
    `ValueError` if the games do not split evenly."""
    r = recipe
    runners = max(env_runners, 1)
    if r.num_envs % runners:
        raise ValueError(f"its {r.num_envs} games do not split over {runners} runners evenly")
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
        "init": "orthogonal",
        "steps": steps,
        "preset_env_options": dict(r.env_options),
    }


#: What `parse_args(presets=...)` takes: a preset's name to its settings for a number of env runners.
Presets = Mapping[str, Callable[[int], dict[str, Any]]]


def parse_args(
    argv: list[str] | None = None, presets: Presets | None = None, description: str | None = None
) -> argparse.Namespace:
    """The trainer's settings from its command line `argv`, checked (exit status 2 with one line naming a bad flag);
    `--preset NAME` is offered when `presets` are given, its settings under the flags given beside it."""
    p = argparse.ArgumentParser(
        prog=None if presets else "python -m chopperscape.integrations.rllib.ppo",
        description=description or "PPO on ChopperScape-v0 with Ray RLlib (new API stack).",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _run_flags(p)
    _game_flags(p, presets)
    _ppo_flags(p)
    _output_flags(p)
    args = p.parse_args(argv)
    _settle(p, args, presets)
    _read_env_and_files(p, args)
    return args


def _run_flags(p: argparse.ArgumentParser) -> None:
    """Where and how long it runs: runners, games, CPUs, the cluster, the budget."""
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


def _game_flags(p: argparse.ArgumentParser, presets: Presets | None) -> None:
    """What it plays: the observation, env options, the seed, and the preset where `presets` are given."""
    p.add_argument("--obs-type", default="features", help="env option obs_type (default: features)")
    p.add_argument("--env-config", default="{}", help="more env options as JSON, e.g. '{\"alien_prob\": 0.1}'")
    p.add_argument("--seed", type=int, default=0, help="RLlib seed (runner w, env i get distinct game seeds)")
    if presets:
        p.add_argument(
            "--preset",
            choices=sorted(presets),
            default=None,
            help="a features preset of chopperscape.learn.train in RLlib's terms (read from its one declaration, "
            "chopperscape.learn.recipe.PRESETS): its games (split over the runners), batch, minibatches, epochs, "
            "lr, gamma, lambda, entropy, clip, hidden width, frame skip and step budget, the recipe's orthogonal "
            "initialisation, and no KL penalty; a flag given here wins",
        )


def _ppo_flags(p: argparse.ArgumentParser) -> None:
    """PPO's settings (unset ones come from the preset or `DEFAULTS`) and this process's threads."""
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
        "--adam-eps",
        type=float,
        default=None,
        help="Adam's epsilon (default torch's 1e-8, RLlib's own; the recipe's is 1e-5); needs the reward scaling",
    )
    p.add_argument(
        "--obs-filter",
        choices=OBS_FILTERS,
        default=None,
        help="how features are normalised: 'synced' (the default: RLlib's MeanStdFilter with an exact merge across "
        "runners) or 'rllib' (RLlib 2.60's own, whose merge pulls the means toward 0 and inflates the stds); "
        "pixels are always scaled to [0, 1]",
    )
    p.add_argument(
        "--init",
        choices=INITS,
        default=None,
        help="the module's initial weights: torch's defaults (RLlib's own, the default) or the recipe's orthogonal "
        "ones (gain sqrt 2, 0.01 in the policy head, 1 in the value head, zero biases; the preset's)",
    )
    p.add_argument(
        "--torch-threads",
        type=int,
        default=1,
        help="torch threads of this process (the learner, and the sampler with 0 runners); runners get "
        "their CPUs' worth from Ray",
    )


def _output_flags(p: argparse.ArgumentParser) -> None:
    """What it writes and evaluates: checkpoints, the summary, the export, the held-out evaluation."""
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


def _settle(p: argparse.ArgumentParser, args: argparse.Namespace, presets: Presets | None) -> None:
    """Fills unset settings from the preset and `DEFAULTS`, then checks each range (exit 2 naming the flag)."""
    settings = dict(DEFAULTS)
    preset = getattr(args, "preset", None)
    if presets and preset is not None:
        try:
            settings.update(presets[preset](args.env_runners))
        except ValueError as e:
            p.error(f"--preset {preset}: {e}")
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
    if args.adam_eps is not None and not 0 < args.adam_eps < 1:
        p.error(f"--adam-eps must be a number in (0, 1), got {args.adam_eps}")
    if args.adam_eps is not None and not args.norm_reward:
        p.error("--adam-eps is set in the reward-scaling learner: it cannot be given with --no-norm-reward")
    if args.iterations is not None and args.iterations < 1:
        p.error(f"--iterations must be >= 1, got {args.iterations}")


def _read_env_and_files(p: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Reads `--env-config` and `--hidden`, and checks `--export` and `--restore` before Ray starts."""
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
        from ...policyfile import check_out

        try:
            check_out(Path(args.export), force=True)
        except ValueError as e:
            p.error(str(e).replace("--out", "--export"))
    if args.restore is not None and not os.path.isdir(args.restore):
        p.error(f"--restore {args.restore!r} is not a directory (give one written by --checkpoint)")
