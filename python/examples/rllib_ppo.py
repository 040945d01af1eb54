#!/usr/bin/env python3
"""PPO on ChopperScape-v0 with Ray RLlib (new API stack), on this machine or on a Ray cluster.

    python python/examples/rllib_ppo.py --minutes 10                    # a local Ray
    ray start --head ...; python python/examples/rllib_ppo.py --address auto ...  # join a running cluster

Its runners, the progress CSV (`--csv`, the single-machine recipe's columns), `--checkpoint`, `--restore` and the
`--summary` JSON are the trainer's: see `chopperscape.integrations.rllib.ppo` and docs/rllib.md.

The trainer is `chopperscape.integrations.rllib.ppo` (`python -m chopperscape.integrations.rllib.ppo`, the bench's
RLlib row); this script adds `--preset` (read from `chopperscape.learn.recipe.PRESETS`) and `--eval-episodes`
(greedy episodes played by `chopperscape.learn.episodes`).
"""

from __future__ import annotations

import argparse
import functools
import sys
from typing import Any

from chopperscape.integrations.rllib import flags, ppo
from chopperscape.learn.recipe import DEFAULT_STEPS, PRESETS, Recipe

#: The trainer's own settings where neither a flag nor `--preset` gives one.
DEFAULTS = flags.DEFAULTS
build_config = ppo.build_config


def preset_settings(name: str, env_runners: int) -> dict[str, Any]:
    """The settings of `chopperscape.learn.train --preset NAME` (features) as the trainer's flags
    (`flags.recipe_settings`): its games split over `env_runners` runners, its step budget and env options, no KL
    penalty. `ValueError` if the games do not split evenly."""
    preset = PRESETS[name]
    recipe = Recipe(**{k: v for k, v in preset.items() if k != "total_steps"})
    return flags.recipe_settings(recipe, preset.get("total_steps", DEFAULT_STEPS), env_runners)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    names = sorted(k for k, v in PRESETS.items() if "obs_type" not in v)
    presets = {name: functools.partial(preset_settings, name) for name in names}
    return flags.parse_args(argv, presets, description=__doc__.split("\n\n")[0])


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


def main(argv: list[str] | None = None) -> int:
    return ppo.main(args=parse_args(argv), evaluate=evaluate)


if __name__ == "__main__":
    sys.exit(main())
