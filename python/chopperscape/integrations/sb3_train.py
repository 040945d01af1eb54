"""Stable-Baselines3 PPO and DQN trainers on ChopperScape through the native adapter: the bench's SB3 rows
(`chopperscape.bench.rows`) and `python/examples/sb3_ppo.py`, `sb3_dqn.py` call them.

    python -m chopperscape.integrations.sb3_train ppo --out runs/sb3 --seed 0 --steps 3000000 \\
        --mode sticky-v0 --settings '{"num_envs": 128, "normalize": true, ...}'

A trainer's settings are one JSON object: what it leaves out is :data:`PPO_DEFAULTS` / :data:`DQN_DEFAULTS` (SB3's
own defaults, written out, and this adapter's), and all of them, defaults included, are recorded. The run writes
`OUT/model.zip`, `OUT/progress.csv` (the return columns of `chopperscape.learn.progress`), with `normalize` the
observation statistics as data in `OUT/vecnormalize.json` (and SB3's pickle `OUT/vecnormalize.pkl`, to go on training
with `VecNormalize.load`), and `OUT/trainer.json` (:data:`RECORD`): the trainer, its full settings, the seed, the
step budget, the env steps trained and the training seeds as the environments were reset with them
(`[[first, count], ...]`; SB3 seeds env `i` with `seed + i`). `--steps` is the budget every schedule follows;
`--minutes` only stops a run early. An env option the mode contradicts (a frame skip) is refused before anything
is written (`ValueError`).
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .. import _atomic, policyfile
from .._cli import print_line, run_command

#: The format of `OUT/trainer.json`.
RECORD = "chopperscape-trainer/1"
#: The progress CSV's columns (`chopperscape.learn.progress.RETURNS`; this layer does not import learn).
COLUMNS = ("env_steps", "wall_s", "episodes", "mean_return", "std_return", "mean_length")

#: PPO's settings where a run gives none: SB3 `PPO`'s own defaults (2.x), on 8 games of features, no normalisation.
#: `lr_floor`: None keeps the learning rate constant; a number anneals it linearly to that fraction of itself
#: (0: to 0 at the budget; the recipe's 0.05: held from 0.95 of it). `clip_anneal`: the clip falls linearly to 0.
PPO_DEFAULTS: dict[str, Any] = {
    "policy": "MlpPolicy",
    "num_envs": 8,
    "env_options": {"obs_type": "features"},
    "normalize": False,
    "learning_rate": 3e-4,
    "lr_floor": None,
    "n_steps": 2048,
    "batch_size": 64,
    "n_epochs": 10,
    "gamma": 0.99,
    "gae_lambda": 0.95,
    "clip_range": 0.2,
    "clip_anneal": False,
    "ent_coef": 0.0,
    "vf_coef": 0.5,
    "max_grad_norm": 0.5,
    "net_arch": None,
}
#: DQN's: SB3 `DQN`'s own defaults but for what this game needs (python/examples/sb3_dqn.py says why): one game of
#: features at frame skip 4, γ 0.998, a 100,000-transition buffer learning from step 10,000, a [128, 128] MLP and
#: observations normalised (rewards left as they are).
DQN_DEFAULTS: dict[str, Any] = {
    "policy": "MlpPolicy",
    "num_envs": 1,
    "env_options": {"obs_type": "features", "frame_skip": 4},
    "normalize": True,
    "learning_rate": 1e-4,
    "buffer_size": 100_000,
    "learning_starts": 10_000,
    "batch_size": 32,
    "tau": 1.0,
    "gamma": 0.998,
    "train_freq": 4,
    "gradient_steps": 1,
    "target_update_interval": 10_000,
    "exploration_fraction": 0.1,
    "exploration_initial_eps": 1.0,
    "exploration_final_eps": 0.05,
    "max_grad_norm": 10,
    "net_arch": [128, 128],
}
_ADAPTER = ("policy", "num_envs", "env_options", "normalize", "lr_floor", "clip_anneal", "net_arch")


def recipe_settings(recipe: Any) -> dict[str, Any]:
    """PPO settings of a features recipe (:class:`chopperscape.learn.recipe.Recipe`, read by attribute): its games,
    env options, rollout, batch, epochs, γ, GAE λ, clip, coefficients, gradient clip, [hidden, hidden] tanh network
    (SB3's MlpPolicy), learning rate annealed to the recipe's `lr_floor` of itself (its schedule), and observations and
    rewards normalised by `VecNormalize` (the recipe's normalisation)."""
    r = recipe
    from .sb3 import ppo_settings

    ppo = ppo_settings(r)  # the adapter's reading of the recipe: rollout, batch, epochs, γ, λ, clip, coefficients
    net_arch = ppo.pop("policy_kwargs")["net_arch"]
    return {
        "policy": "MlpPolicy",
        "num_envs": r.num_envs,
        "env_options": {"obs_type": "features", **dict(r.env_options)},
        "normalize": True,
        "learning_rate": r.learning_rate,
        "lr_floor": r.lr_floor,
        **ppo,
        "clip_anneal": False,
        "net_arch": net_arch,
    }


def settings_of(algo: str, given: Mapping[str, Any]) -> dict[str, Any]:
    """`given` over the defaults of `algo` ("ppo", "dqn"); `ValueError` naming a setting the trainer does not have."""
    defaults = {"ppo": PPO_DEFAULTS, "dqn": DQN_DEFAULTS}[algo]
    unknown = sorted(set(given) - set(defaults))
    if unknown:
        raise ValueError(f"{algo} setting {unknown[0]!r} is unknown: allowed {', '.join(sorted(defaults))}")
    return {**defaults, **given}


def seed_ranges(seeds: list[int | None] | None) -> list[list[int]]:
    """Reset seeds as sorted ranges `[first, count]` (`policyfile.seed_ranges`); `ValueError` if there are none."""
    if not seeds:
        raise ValueError("an environment was reset without a seed: its training seeds are unknown")
    return [list(r) for r in policyfile.seed_ranges(seeds)]


def progress_callback(path: Path, minutes: float | None, every: int = 0) -> Any:
    """An SB3 callback writing one progress CSV row per rollout (the last 100 episodes), at most one every `every`
    env steps (DQN's rollouts are 4 steps long), and stopping the run after `minutes`."""
    from stable_baselines3.common.callbacks import BaseCallback

    class ProgressCsv(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.deadline = float("inf") if minutes is None else minutes * 60
            self.start = time.monotonic()
            self.episodes, self.last = 0, -every

        def _on_training_start(self) -> None:
            path.parent.mkdir(parents=True, exist_ok=True)
            self.file = open(path, "w", newline="")
            self.csv = csv.writer(self.file)
            self.csv.writerow(COLUMNS)

        def _on_step(self) -> bool:
            self.episodes += sum("episode" in i for i in self.locals["infos"])
            return time.monotonic() - self.start < self.deadline

        def _on_rollout_end(self) -> None:
            eps = list(self.model.ep_info_buffer or [])
            if eps and self.num_timesteps - self.last >= every:
                self.last = self.num_timesteps
                r, n = np.array([e["r"] for e in eps]), np.array([e["l"] for e in eps])
                wall = f"{time.monotonic() - self.start:.1f}"
                stats = [f"{r.mean():.1f}", f"{r.std():.1f}", f"{n.mean():.1f}"]
                self.csv.writerow([self.num_timesteps, wall, self.episodes, *stats])
                self.file.flush()

        def _on_training_end(self) -> None:
            self.file.close()

    return ProgressCsv()


def _env(settings: Mapping[str, Any], seed: int, mode: str | None) -> Any:
    from .sb3 import ChopperScapeVecEnv

    options = dict(settings["env_options"])
    if mode is not None:
        options["mode"] = mode
    return ChopperScapeVecEnv(settings["num_envs"], seed=seed, **options)


def _schedule(value: float, floor: float | None) -> Any:
    return value if floor is None else (lambda remaining: value * max(remaining, floor))


def train(
    algo: str,
    out: str | Path,
    settings: Mapping[str, Any] | None = None,
    *,
    seed: int = 0,
    steps: int,
    mode: str | None = None,
    minutes: float | None = None,
    torch_threads: int = 1,
) -> dict[str, Any]:
    """Trains SB3's `algo` ("ppo" or "dqn") with `settings` (over the defaults) for `steps` env steps (decisions)
    from `seed` on `mode`'s rules into `out` (see the module's docs); returns what `OUT/trainer.json` holds."""
    import torch
    from stable_baselines3 import DQN, PPO
    from stable_baselines3.common.vec_env import VecNormalize

    from .sb3_files import save_normalization

    s = settings_of(algo, settings or {})
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise ValueError(f"--steps {steps!r}: at least 1")
    torch.set_num_threads(torch_threads)
    venv = _env(s, seed, mode)  # a mode that contradicts an option is refused here, before anything is written
    env: Any = venv
    if s["normalize"]:
        env = VecNormalize(venv, gamma=s["gamma"], norm_reward=algo == "ppo")
    kwargs = {k: v for k, v in s.items() if k not in _ADAPTER}
    policy_kwargs: dict[str, Any] = (
        {} if s["net_arch"] is None else {"policy_kwargs": {"net_arch": list(s["net_arch"])}}
    )
    if algo == "ppo":
        kwargs["learning_rate"] = _schedule(s["learning_rate"], s["lr_floor"])
        if s["clip_anneal"]:
            kwargs["clip_range"] = _schedule(s["clip_range"], 0.0)
        model: Any = PPO(s["policy"], env, **kwargs, **policy_kwargs, seed=seed, device="cpu")
    else:
        model = DQN(s["policy"], env, **kwargs, **policy_kwargs, seed=seed, device="cpu")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    every = 10_000 if algo == "dqn" else 0
    model.learn(steps, callback=progress_callback(out / "progress.csv", minutes, every))
    model.save(out / "model.zip", exclude=["replay_buffer"] if algo == "dqn" else None)
    if s["normalize"]:
        save_normalization(env, out / "vecnormalize.json")
        env.save(str(out / "vecnormalize.pkl"))
    record = {
        "format": RECORD,
        "trainer": f"sb3-{algo}",
        "settings": s,
        "seed": seed,
        "mode": mode,
        "steps": steps,
        "env_steps": int(model.num_timesteps),
        "train_seeds": seed_ranges(venv.reset_seeds),
    }
    _atomic.write_text(out / "trainer.json", json.dumps(record, indent=2, sort_keys=True) + "\n")
    return record


def main(argv: list[str] | None = None) -> int:
    prog = "python -m chopperscape.integrations.sb3_train"
    p = argparse.ArgumentParser(prog=prog, description=__doc__.split("\n")[0])
    p.add_argument("algo", choices=("ppo", "dqn"))
    p.add_argument("--out", type=Path, required=True, help="folder for model.zip, progress.csv, trainer.json")
    p.add_argument("--steps", type=int, required=True, help="env-step budget (decisions; the schedules follow it)")
    p.add_argument("--seed", type=int, default=0, help="env i's first reset seed is SEED + i; SB3's seed")
    p.add_argument("--mode", default=None, help="a bench mode's rules (default v0's)")
    p.add_argument("--settings", default="{}", help="the trainer's settings as a JSON object (over the defaults)")
    p.add_argument("--minutes", type=float, default=None, help="stop after this much wall time")
    p.add_argument("--torch-threads", type=int, default=1)
    a = p.parse_args(argv)

    def command() -> int:
        try:
            given = json.loads(a.settings)
        except ValueError as e:
            raise ValueError(f"--settings is not JSON ({e}): give an object such as '{{\"n_epochs\": 4}}'") from None
        if not isinstance(given, dict):
            raise ValueError("--settings must be a JSON object such as '{\"n_epochs\": 4}'")
        record = train(a.algo, a.out, given, seed=a.seed, steps=a.steps, mode=a.mode, minutes=a.minutes)
        return print_line(f"{a.out}: {record['env_steps']} env steps, training seeds {record['train_seeds']}")

    return run_command(command)


if __name__ == "__main__":
    sys.exit(main())
