"""Stable-Baselines3 PPO on ChopperScape through the native adapter, writing the recipe's progress CSV.

    python python/examples/sb3_ppo.py --minutes 30 --out runs/sb3-default                # SB3's defaults
    python python/examples/sb3_ppo.py --steps 15000000 --out runs/sb3-tuned --tuned      # the recipe's settings in SB3
    python python/examples/sb3_ppo.py --pixels 42 --steps 2000000 --out runs/sb3-pixels42  # CnnPolicy on frames
    python python/examples/sb3_ppo.py --preset fast --mode sticky-v0 --out runs/sb3-fast  # the fast preset in SB3

`--pixels SIZE` is what a pixel-RL user tries first: SB3's `CnnPolicy` (the Nature CNN) with RL Zoo's Atari PPO
settings (8 envs × 128 steps, 4 epochs of batches of 256, learning rate 2.5e-4 and clip 0.1 both annealed linearly,
entropy 0.01, γ 0.99) on the agent view: SIZE×SIZE grayscale frames, 4 stacked, each action held 4 frames (env steps
count decisions). Evaluate it with the same options: ``python -m chopperscape.learn.evaluate OUT/model.zip --option
obs_type='"grayscale"' --option obs_size=[42,42] --option frame_stack=4 --option frame_skip=4``.

`--tuned` uses what ``chopperscape.learn.train`` uses, read from :class:`chopperscape.learn.recipe.Recipe`'s defaults
(γ, GAE λ, 64 envs × 256 steps, 8 minibatches, 4 epochs, clip, entropy and value coefficients, gradient clip,
[128, 128] tanh, the learning rate annealed linearly to 5 % over ``--steps``, observations and rewards normalised by
``VecNormalize``). ``--preset fast`` does the same with the fast preset's settings, frame skip 4 and its 3 M decisions.
``--steps`` is the budget every schedule follows; ``--minutes`` only stops a run early.
The model is saved as ``OUT/model.zip`` (and, with
``--tuned``, the normalisation statistics as data in ``OUT/vecnormalize.json``, which
``python -m chopperscape.learn.evaluate OUT/model.zip`` reads, and as SB3's pickle in ``OUT/vecnormalize.pkl``, to go on
training with ``VecNormalize.load``); ``progress.csv`` has the return columns of
:mod:`chopperscape.learn.progress`, drawn by ``python -m chopperscape.learn.plot``. The trainer is
``chopperscape.integrations.sb3_train`` (``OUT/trainer.json`` records its full settings and the training seeds).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from chopperscape import MODES
from chopperscape.integrations.sb3_train import recipe_settings, train
from chopperscape.learn.recipe import PRESETS, Recipe


def pixel_settings(size: int) -> dict[str, Any]:
    """RL Zoo's Atari PPO on SIZE x SIZE grayscale frames, 4 stacked, frame skip 4 (the module's docs)."""
    return {
        "policy": "CnnPolicy",
        "num_envs": 8,
        "env_options": {"obs_type": "grayscale", "obs_size": [size, size], "frame_stack": 4, "frame_skip": 4},
        "n_steps": 128,
        "n_epochs": 4,
        "batch_size": 256,
        "learning_rate": 2.5e-4,
        "lr_floor": 0.0,
        "clip_range": 0.1,
        "clip_anneal": True,
        "ent_coef": 0.01,
        "vf_coef": 0.5,
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, required=True)
    p.add_argument("--steps", type=int, default=None, help="env-step budget (the schedules follow it)")
    p.add_argument(
        "--minutes", type=float, default=None, help="stop after this much wall time (default 30 without --steps)"
    )
    p.add_argument("--tuned", action="store_true", help="the recipe's hyperparameters instead of SB3's defaults")
    p.add_argument(
        "--preset",
        choices=("features", "fast"),
        default=None,
        help="a features preset's hyperparameters, frame skip and step budget (--tuned is --preset features)",
    )
    p.add_argument(
        "--pixels", type=int, default=None, metavar="SIZE", help="CnnPolicy on SIZE x SIZE frames, RL Zoo's Atari PPO"
    )
    p.add_argument(
        "--mode", choices=[m["name"] for m in MODES], default=None, help="a bench mode's rules (default v0's)"
    )
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--torch-threads", type=int, default=1, help="torch threads (1 is fastest for these small MLPs)")
    a = p.parse_args()
    if a.tuned and a.preset not in (None, "features"):
        p.error(f"--tuned is --preset features, not --preset {a.preset}: give one")
    preset = "features" if a.tuned else a.preset
    if preset is not None and a.steps is None:
        a.steps = PRESETS[preset].get("total_steps")
    if a.steps is None and a.minutes is None:
        a.minutes = 30.0
    if preset is not None and a.pixels is not None:
        p.error("--tuned and --preset are the features recipe's settings; --pixels has RL Zoo's Atari settings")
    if a.pixels is not None and not 36 <= a.pixels <= 600:
        p.error(f"--pixels {a.pixels}: the Nature CNN needs frames of 36 to 600 pixels a side")
    settings: dict[str, Any] = {}
    if a.pixels is not None:
        settings, flag = pixel_settings(a.pixels), "--pixels"
    elif preset is not None:
        recipe = Recipe(**{k: v for k, v in PRESETS[preset].items() if k != "total_steps"})
        settings, flag = recipe_settings(recipe), f"--preset {preset}"
    else:
        flag = "--mode"
    try:
        train(
            "ppo",
            a.out,
            settings,
            seed=a.seed,
            steps=a.steps or 10**10,
            mode=a.mode,
            minutes=a.minutes,
            torch_threads=a.torch_threads,
        )
    except ValueError as e:  # a mode whose frame skip is not the settings'
        p.error(f"{flag}: {e}")


if __name__ == "__main__":
    main()
