"""The evaluation protocol of ChopperScape-Bench, stated once. Every results file carries `PROTOCOL`; the report
refuses to compare files of different protocols.

- **Evaluation seeds**: episodes `k = 0 … 99` are played from `reset(seed=1_000_000 + k)` (the held-out seeds of
  `chopperscape.learn.evaluate` and `learn.seeds`). Nobody trains on them: a training run's reset seeds
  (`seed, seed + 1, …, seed + num_envs − 1` for `chopperscape.learn.train` and the SB3 adapter) must lie outside
  `[1_000_000, 1_000_100)`; :func:`check_training_seeds` refuses a run whose seeds overlap.
- **Episodes per evaluation**: 100, each played to its end or to the step limit.
- **Step limit**: 10,000 agent steps (Gymnasium's `TimeLimit`, the registered `max_episode_steps`), whatever the
  frame skip.
- **Actions**: a trained policy acts greedily (argmax of its logits, SB3's `deterministic=True`); a built-in policy
  acts as it is (`random` draws from its own generator). `--stochastic` samples a trained policy's actions instead
  and is recorded as such (`"actions": "sampled"`), a different protocol row.
- **Runs**: one results file is one run (one trained model, or one policy seed). A stochastic policy is evaluated
  on 10 policy seeds (`--policy-seed 0 … 9`): run `r`'s policy for episode `k` is seeded `r · 2**32 + k`. A
  deterministic one (the heuristic) gives the same file for every policy seed: one run. A row of trained policies
  (one recipe's training seeds, under one `--name`) is 10 runs, one per training seed; one trained model alone is
  one run. The report checks every row it prints against this count (`report.runs_required`).
- **Score**: a run's score is its mean return over the 100 episodes; the aggregates normalise it by the most a
  mode allows (`10,000 × frame_skip`: +1 per underlying step up to the step limit), so 1.0 is a perfect run and the
  optimality gap is taken at γ = 1.
- **Observation**: free (features or pixels, any size or stack): a rung fixes the rules, not what the agent sees.
"""

from __future__ import annotations

from typing import Any

from ..modes import mode_options

#: The version of this protocol: a change to anything below is a new version.
VERSION = 1
EVAL_SEED = 1_000_000
EVAL_EPISODES = 100
MAX_EPISODE_STEPS = 10_000
#: Policy seeds of the runs of a stochastic policy.
POLICY_SEEDS = tuple(range(10))
#: The runs of a stochastic policy (its policy seeds) and of a trained row (its training seeds); a deterministic
#: policy alone is one run.
RUNS = 10
#: The built-in policies that draw from their generator (the others act on the state alone: deterministic).
STOCHASTIC_BUILTINS = ("random",)
#: Run `r`'s policy for episode `k` is seeded `r * POLICY_SEED_STRIDE + k`.
POLICY_SEED_STRIDE = 2**32

#: What every results file carries as its `protocol` (compared whole by the report).
PROTOCOL: dict[str, Any] = {
    "version": VERSION,
    "eval_seeds": {"first": EVAL_SEED, "count": EVAL_EPISODES},
    "episodes": EVAL_EPISODES,
    "max_episode_steps": MAX_EPISODE_STEPS,
    "score": "mean return over the episodes, normalised by max_episode_steps * frame_skip",
}


def eval_seeds() -> range:
    """The evaluation seeds, `range(1_000_000, 1_000_100)`."""
    return range(EVAL_SEED, EVAL_SEED + EVAL_EPISODES)


def check_training_seeds(first: int, count: int = 1, what: str = "training") -> None:
    """Refuses (`ValueError`) training reset seeds `first … first + count − 1` that reach the evaluation seeds."""
    if count < 1:
        raise ValueError(f"{what} seeds: count {count} must be >= 1")
    seeds = eval_seeds()
    lo, hi = max(first, seeds.start), min(first + count, seeds.stop)
    if lo < hi:
        raise ValueError(
            f"{what} seeds {first}..{first + count - 1} overlap the evaluation seeds "
            f"{seeds.start}..{seeds.stop - 1} (seed {lo}): train on other seeds (the protocol, docs/site/bench.md)"
        )


def max_return(name: str) -> int:
    """The most an episode of mode `name` can return under the protocol: +1 per underlying step to the limit."""
    return MAX_EPISODE_STEPS * int(mode_options(name)["frame_skip"])


def policy_seed(run: int, episode: int) -> int:
    """The seed of run `run`'s policy for episode `episode` (stochastic policies)."""
    return run * POLICY_SEED_STRIDE + episode
