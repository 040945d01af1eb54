"""The recipe's initialisation for RLlib's default PPO module (`--init orthogonal`): orthogonal weights with gain
√2 in the encoders, 0.01 in the policy head and 1 in the value head, zero biases, as the recipe's
:class:`chopperscape.learn.networks.Agent` and SB3's `ortho_init` have them. RLlib's `DefaultModelConfig` leaves its
initialisers to torch's defaults and takes one initialiser for both heads, so the module is re-initialised in the
learner after it is built, and the runners are then given its weights."""

from __future__ import annotations

import math
from typing import Any

#: `--init` choices: RLlib's own (torch's defaults) or the recipe's.
INITS = ("torch", "orthogonal")

#: Gains of the last layer of each head, by the name RLlib's PPO module gives the head.
HEAD_GAINS = {"pi": 0.01, "vf": 1.0}


def gain(name: str) -> float:
    """The orthogonal gain of the layer called `name` in the module (`pi.net.mlp.0`, `encoder.actor_encoder…`)."""
    return HEAD_GAINS.get(name.split(".", 1)[0], math.sqrt(2))


def orthogonal(module: Any) -> int:
    """Re-initialises every linear and convolution layer of the torch `module` by its place; returns how many.
    Draws from torch's generator, which RLlib seeds from `config.seed`, so a seed gives the same weights."""
    import torch

    count = 0
    with torch.no_grad():
        for name, layer in module.named_modules():
            if isinstance(layer, (torch.nn.Linear, torch.nn.Conv2d)):
                torch.nn.init.orthogonal_(layer.weight, gain(name))
                if layer.bias is not None:
                    layer.bias.zero_()
                count += 1
    return count


def _learner_orthogonal(learner: Any) -> int:
    return sum(orthogonal(learner.module[m]) for m in learner.module.keys())


def initialise(algo: Any, init: str) -> int:
    """Applies `init` (one of `INITS`) to a freshly built algorithm's learners and syncs the runners; returns the
    layers re-initialised (0 for `torch`, which leaves RLlib's module as built)."""
    if init not in INITS:
        raise ValueError(f"init must be one of {', '.join(INITS)}, got {init!r}")
    if init == "torch":
        return 0
    counts = [r.get() for r in algo.learner_group.foreach_learner(_learner_orthogonal)]
    algo.env_runner_group.sync_weights(from_worker_or_learner_group=algo.learner_group, inference_only=True)
    return int(counts[0])
