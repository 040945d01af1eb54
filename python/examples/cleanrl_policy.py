"""The policy of `cleanrl_ppo.py`'s saved weights, as the bench plays a callable policy (a *policy factory*):

    PYTHONPATH=python/examples python -m chopperscape.bench evaluate cleanrl_policy:policy --mode sticky-v0 \
        --policy-arg weights=runs/cleanrl/seed-0/weights.pt --train-seeds 0:8 --name "..." --out FILE

(with `python/examples` on `PYTHONPATH`, so that this module imports; not `python/`, whose `chopperscape` sources
lack the compiled core and would shadow the installed package). The bench calls
`policy(seed=R, stochastic=..., weights=...)` once per run: `R` is `--policy-seed`, `stochastic` is `--stochastic`
(sample from the logits with a generator seeded `R`, instead of their argmax), `weights` is a `--policy-arg`. `FILES`
declares the file the policy reads, named by its `weights` argument: the results file records its SHA-256 with this
module's.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

#: The files this policy reads, each formatted with its policy arguments: hashed into the results file.
FILES = ["{weights}"]


def policy(*, seed: int, stochastic: bool = False, weights: str) -> Callable[[np.ndarray], np.ndarray]:
    """The batch policy of the actor weights `weights` (`torch.load(weights_only=True)`: tensors only)."""
    import torch
    from torch import nn

    state = torch.load(weights, map_location="cpu", weights_only=True)
    layers = sorted({int(k.split(".")[0]) for k in state})
    modules: list[nn.Module] = []
    for i, n in enumerate(layers):
        out_dim, in_dim = state[f"{n}.weight"].shape
        modules.append(nn.Linear(in_dim, out_dim))
        if i < len(layers) - 1:
            modules.append(nn.Tanh())
    net = nn.Sequential(*modules)
    net.load_state_dict(state)
    net.eval()
    torch.set_num_threads(1)  # a tiny network: one thread is the fastest
    gen = torch.Generator().manual_seed(seed)

    def act(obs: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            logits = net(torch.as_tensor(obs, dtype=torch.float32).reshape(len(obs), -1))
        if stochastic:
            return torch.multinomial(logits.softmax(-1), 1, generator=gen).squeeze(1).numpy()
        return logits.argmax(-1).numpy()

    return act
