"""Stable-Baselines3 DQN on ChopperScape's features through the native adapter, writing the recipe's progress CSV.

    python python/examples/sb3_dqn.py --mode sticky-v0 --steps 1000000 --out runs/sb3-dqn

A stock DQN (Mnih et al. 2015 as SB3 implements it), the anchor an off-policy user would pick: one env, SB3's
defaults (Adam 1e-4, batches of 32 every 4 steps, target network copied every 10,000 steps, ε from 1 to 0.05 over
the first 10 % of the budget, Huber loss, gradient norm 10) but for what this game needs: γ 0.998 a decision (the
features recipe's horizon at frame skip 4, since fuel lasts 250 decisions), a 100,000-transition replay buffer
learning from step 10,000, the recipe's [128, 128] MLP, and observations normalised by ``VecNormalize`` (rewards
left as they are: Q-learning's targets need the true scale). Frame skip 4 unless the mode says otherwise (a mode
with frame skip 1 is refused: one decision a frame would need four times the budget). The model is saved as
``OUT/model.zip`` with the normalisation as data in ``OUT/vecnormalize.json``, which ``python -m
chopperscape.learn.evaluate OUT/model.zip`` and ``python -m chopperscape.bench evaluate OUT/model.zip --option
obs_type='"features"'`` read without unpickling; ``--steps`` is the budget every schedule follows. The trainer is
``chopperscape.integrations.sb3_train`` (its settings: ``DQN_DEFAULTS``; ``OUT/trainer.json`` records them and the
training seeds).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from chopperscape import MODES
from chopperscape.integrations.sb3_train import train


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, required=True)
    p.add_argument("--steps", type=int, default=1_000_000, help="env-step budget (decisions; schedules follow it)")
    p.add_argument("--mode", choices=[m["name"] for m in MODES], default=None, help="a bench mode's rules")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--torch-threads", type=int, default=1)
    a = p.parse_args()
    if a.steps < 1:
        p.error(f"--steps {a.steps}: at least 1")
    try:
        train("dqn", a.out, seed=a.seed, steps=a.steps, mode=a.mode, torch_threads=a.torch_threads)
    except ValueError as e:  # a mode whose frame skip is not 4
        p.error(f"--mode {a.mode}: {e}")


if __name__ == "__main__":
    main()
