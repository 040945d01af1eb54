"""Writes the goldens that crates/learn's tests check the Rust learner against, from Python's own code:

- ``recipe.json``: ``asdict(Recipe(**PRESETS[name]))`` for the presets the Rust learner trains (``fast``,
  ``features``), the values ``recipe.json`` of a run holds;
- ``batch.json``: one small batch through Python's implementation: ``normalize.RunningMeanStd`` and
  ``normalize.ObsNormalizer`` (their update and output), GAE as ``rollout.advantages`` computes it (NEXT_STEP
  autoreset, reset steps masked), and the PPO loss of a ``networks.Agent`` on a minibatch with its gradients
  (``train.py``'s lines).

Regenerate (from the repository root, with the package and torch installed):

    python crates/learn/tests/golden/make_golden.py
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np
import torch

from chopperscape.learn.networks import Agent
from chopperscape.learn.normalize import ObsNormalizer, RunningMeanStd
from chopperscape.learn.recipe import PRESETS, Recipe

HERE = Path(__file__).parent


def recipes() -> dict:
    return {name: asdict(Recipe(**PRESETS[name])) for name in ("fast", "features")}


def gae(rew, val, done, valid, next_value, gamma, lam):
    """`rollout.advantages`'s GAE, on tensors of shape (T, N) (before the batch drops the reset steps)."""
    t_len, n = rew.shape
    adv = torch.zeros((t_len, n))
    last = torch.zeros(n)
    for t in reversed(range(t_len)):
        nv = next_value if t == t_len - 1 else val[t + 1]
        nonterminal = 1.0 - done[t]
        delta = rew[t] + gamma * nv * nonterminal - val[t]
        last = delta + gamma * lam * nonterminal * last
        last = last * valid[t]
        adv[t] = last
    return adv, adv + val


def batch() -> dict:
    rng = np.random.default_rng(7)
    torch.manual_seed(7)
    # Normalisers.
    obs = rng.normal(3.0, 2.0, size=(6, 4)).astype(np.float32)
    norm = ObsNormalizer((4,))
    first = norm(obs[:3], update=True)
    second = norm(obs[3:], update=True)
    # GAE.
    t_len, n = 5, 3
    rew = torch.tensor(rng.normal(size=(t_len, n)), dtype=torch.float32)
    val = torch.tensor(rng.normal(size=(t_len, n)), dtype=torch.float32)
    done = torch.tensor(rng.random((t_len, n)) < 0.3, dtype=torch.float32)
    valid = torch.ones((t_len, n))
    valid[1:] = 1.0 - done[:-1]  # the step after an end is its reset step
    next_value = torch.tensor(rng.normal(size=n), dtype=torch.float32)
    adv, ret = gae(rew, val, done, valid, next_value, 0.998, 0.98)
    # The loss of a small agent on a minibatch, and its gradients.
    agent = Agent(4, 5, 8)
    with torch.no_grad():  # larger heads than the recipe's 0.01 gain, so the ratio moves and clipping happens
        agent.actor[4].weight.mul_(100.0)
    m = 12
    x = torch.tensor(rng.normal(size=(m, 4)), dtype=torch.float32)
    act = torch.tensor(rng.integers(0, 5, m))
    old_logp = torch.tensor(np.log(rng.uniform(0.1, 0.3, m)), dtype=torch.float32)
    b_adv = torch.tensor(rng.normal(size=m), dtype=torch.float32)
    b_ret = torch.tensor(rng.normal(size=m), dtype=torch.float32)
    clip, ent_coef, vf_coef = 0.2, 0.02, 0.5
    logits, value, _ = agent.heads(x)
    dist = torch.distributions.Categorical(logits=logits)
    logp, entropy = dist.log_prob(act), dist.entropy()
    log_ratio = logp - old_logp
    ratio = log_ratio.exp()
    a = (b_adv - b_adv.mean()) / (b_adv.std() + 1e-8)
    pg = torch.max(-a * ratio, -a * ratio.clamp(1 - clip, 1 + clip)).mean()
    v_loss = 0.5 * ((value - b_ret) ** 2).mean()
    ent = entropy.mean()
    loss = pg - ent_coef * ent + vf_coef * v_loss
    loss.backward()
    params = [p for part in (agent.actor, agent.critic) for p in part.parameters()]
    return {
        "obs": obs.tolist(),
        "norm_first": first.tolist(),
        "norm_second": second.tolist(),
        "rms": norm.rms.state(),
        "gae": {
            "rewards": rew.tolist(),
            "values": val.tolist(),
            "done": done.tolist(),
            "valid": valid.tolist(),
            "next_value": next_value.tolist(),
            "gamma": 0.998,
            "lambda": 0.98,
            "advantages": adv.tolist(),
            "returns": ret.tolist(),
        },
        "loss": {
            # torch's layout: weights (outputs, inputs); actor's three layers, then the critic's.
            "params": [p.detach().flatten().tolist() for p in params],
            "shapes": [list(p.shape) for p in params],
            "obs": x.tolist(),
            "actions": act.tolist(),
            "old_logp": old_logp.tolist(),
            "advantages": b_adv.tolist(),
            "returns": b_ret.tolist(),
            "clip": clip,
            "ent_coef": ent_coef,
            "vf_coef": vf_coef,
            "total": loss.item(),
            "policy": pg.item(),
            "value": v_loss.item(),
            "entropy": ent.item(),
            "approx_kl": ((ratio - 1) - log_ratio).mean().item(),
            "clip_frac": ((ratio - 1).abs() > clip).float().mean().item(),
            "grads": [p.grad.flatten().tolist() for p in params],
        },
    }


if __name__ == "__main__":
    RunningMeanStd  # noqa: B018  (the normaliser's statistics: normalize.RunningMeanStd, Gymnasium's update)
    (HERE / "recipe.json").write_text(json.dumps(recipes(), indent=2) + "\n")
    (HERE / "batch.json").write_text(json.dumps(batch(), indent=1) + "\n")
    print("wrote", HERE / "recipe.json", HERE / "batch.json")
