"""The network as the training loop calls it (`Recipe.torch_compile`): eager torch, or the same network's heads
through `torch.compile`, so that Inductor fuses the frames' cast and scaling, the ReLUs and the heads' small layers
around the convolutions, forward and backward.

Each batch is padded with blank frames to one fixed size before the compiled call and the outputs are cut back:
the rollout's batch is always `num_envs`, but the update's minibatches vary by a few samples (reset steps are left
out), and a compiled graph specialised to one size is faster here than one with symbolic sizes (measured:
docs/notes/pixels-speed-and-probes.md). The padded rows' outputs are dropped, so they add nothing to the loss or
its gradients. Sampling stays eager: :func:`~.networks.act_on`, what :meth:`ActorCritic.act` calls.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any, NamedTuple

import torch

from .networks import ActorCritic, act_on
from .recipe import Recipe

#: `heads(x)`: `(logits, value, embedding)` as :meth:`ActorCritic.heads` gives them.
Heads = Callable[[torch.Tensor], tuple[torch.Tensor, torch.Tensor, torch.Tensor | None]]


class Network(NamedTuple):
    """What the loop calls of the network: `act` in the rollout (:func:`~.networks.act_on`: the action, its
    log-probability, the entropy, the value and the embedding), `heads` in the update."""

    act: Callable[[torch.Tensor], tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor | None]]
    heads: Heads


def padded(heads: Heads, size: int) -> Heads:
    """`heads` called on batches padded with zeros to `size` rows, its outputs cut back to the batch's rows."""

    def call(x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor | None]:
        n = int(x.shape[0])
        if n > size:
            raise ValueError(f"a batch of {n} rows is larger than the compiled size {size}")
        if n < size:
            x = torch.cat([x, x.new_zeros((size - n, *x.shape[1:]))])
        logits, value, h = heads(x)
        return logits[:n], value[:n], None if h is None else h[:n]

    return call


def network_for(recipe: Recipe, agent: ActorCritic) -> Network:
    """The agent's `act` and `heads` as `recipe` runs them: eager, or compiled for the rollout's batch
    (`num_envs`) and the update's largest minibatch."""
    if not recipe.torch_compile:
        return Network(partial(act_on, agent.heads), agent.heads)
    compiled: Any = torch.compile(agent.heads, dynamic=False, fullgraph=True)
    batch = recipe.num_envs * recipe.num_steps
    minibatch = -(-batch // recipe.num_minibatches)
    rollout = padded(compiled, recipe.num_envs)
    return Network(lambda x: act_on(rollout, x), padded(compiled, minibatch))
