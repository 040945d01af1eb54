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
:mod:`chopperscape.learn.progress`, drawn by ``python -m chopperscape.learn.plot``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecNormalize

from chopperscape import MODES
from chopperscape.integrations.sb3 import ChopperScapeVecEnv, ppo_settings, save_normalization
from chopperscape.learn import progress
from chopperscape.learn.recipe import LR_FLOOR, PRESETS, Recipe


class ProgressCsv(BaseCallback):
    """Writes one CSV row per rollout (last 100 episodes), at most one every `every` env steps (DQN's rollouts are
    4 steps long), and stops at the time budget."""

    def __init__(self, path: Path, minutes: float | None, every: int = 0):
        super().__init__()
        self.path, self.deadline = path, float("inf") if minutes is None else minutes * 60
        self.start = time.monotonic()
        self.episodes = 0
        self.every, self.last = every, -every

    def _on_training_start(self) -> None:
        self.writer = progress.Writer(self.path, progress.RETURNS)

    def _on_step(self) -> bool:
        self.episodes += sum("episode" in i for i in self.locals["infos"])
        return time.monotonic() - self.start < self.deadline

    def _on_rollout_end(self) -> None:
        eps = list(self.model.ep_info_buffer or [])
        if eps and self.num_timesteps - self.last >= self.every:
            self.last = self.num_timesteps
            r = np.array([e["r"] for e in eps])
            length = np.array([e["l"] for e in eps])
            self.writer.row(
                {
                    "env_steps": self.num_timesteps,
                    "wall_s": f"{time.monotonic() - self.start:.1f}",
                    "episodes": self.episodes,
                    "mean_return": f"{r.mean():.1f}",
                    "std_return": f"{r.std():.1f}",
                    "mean_length": f"{length.mean():.1f}",
                }
            )

    def _on_training_end(self) -> None:
        self.writer.close()


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
    steps = a.steps or 10**10
    torch.set_num_threads(a.torch_threads)
    rules = {} if a.mode is None else {"mode": a.mode}
    if preset is not None and a.pixels is not None:
        p.error("--tuned and --preset are the features recipe's settings; --pixels has RL Zoo's Atari settings")
    if a.pixels is not None and not 36 <= a.pixels <= 600:
        p.error(f"--pixels {a.pixels}: the Nature CNN needs frames of 36 to 600 pixels a side")
    if a.pixels is not None:
        frames = {"obs_size": [a.pixels, a.pixels], "frame_stack": 4, "frame_skip": 4}
        try:
            env = ChopperScapeVecEnv(8, seed=a.seed, obs_type="grayscale", **frames, **rules)
        except ValueError as e:  # a mode whose frame skip is not 4
            p.error(f"--pixels: {e}")
        model = PPO(
            "CnnPolicy",
            env,
            n_steps=128,
            n_epochs=4,
            batch_size=256,
            learning_rate=lambda remaining: 2.5e-4 * remaining,
            clip_range=lambda remaining: 0.1 * remaining,
            ent_coef=0.01,
            vf_coef=0.5,
            seed=a.seed,
            device="cpu",
        )
    elif preset is not None:
        r = Recipe(**{k: v for k, v in PRESETS[preset].items() if k != "total_steps"})
        try:
            venv = ChopperScapeVecEnv(r.num_envs, seed=a.seed, obs_type="features", **r.env_options, **rules)
        except ValueError as e:  # a mode whose frame skip is not the preset's
            p.error(f"--preset {preset}: {e}")
        env = VecNormalize(venv, gamma=r.gamma)
        lr = r.learning_rate
        model = PPO(
            "MlpPolicy",
            env,
            learning_rate=lambda remaining: lr * max(remaining, LR_FLOOR),
            **ppo_settings(r),
            seed=a.seed,
            device="cpu",
        )
    else:
        env = ChopperScapeVecEnv(8, seed=a.seed, obs_type="features", **rules)
        model = PPO("MlpPolicy", env, seed=a.seed, device="cpu")
    a.out.mkdir(parents=True, exist_ok=True)
    model.learn(steps, callback=ProgressCsv(a.out / "progress.csv", a.minutes))
    model.save(a.out / "model.zip")
    if preset is not None:
        save_normalization(env, a.out / "vecnormalize.json")
        env.save(str(a.out / "vecnormalize.pkl"))


if __name__ == "__main__":
    main()
