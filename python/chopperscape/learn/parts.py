"""The recipe's variants, decided once: :func:`parts_of` reads a :class:`~.recipe.Recipe` and returns the
:class:`Parts` the training loop calls — the network, how an observation batch becomes its input, what the update
does to each minibatch, and the guidance from the game's features — so that the loop never asks which variant it
runs. Plain PPO's guidance is :class:`Unguided`, which does nothing; the features twin, auxiliary head and teacher
(:mod:`.guidance`) are imported only for a recipe that asks for them. The self-supervised loss from the frames
(:mod:`.selfsup`) and the exploration bonus from the frames (:mod:`.novelty`) are parts of their own, apart from
the guidance: they read nothing but the frames.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple, cast

import numpy as np
import torch

from .. import NUM_ACTIONS
from ..vector import VectorEnv
from .augment import augmentation
from .compiled import Network, network_for
from .networks import ActorCritic, CnnAgent, build_agent, parameter_count
from .normalize import ObsNormalizer
from .novelty import novelty_of
from .recipe import MAX_PARAMETERS, MAX_ROLLOUT_BYTES, Recipe, network_of
from .rollout import Rollout
from .selfsup import frames_loss


class Unguided:
    """Plain PPO's guidance: no twin env, no added loss, no columns, no state."""

    feat_dim = 0

    @property
    def params(self) -> list[torch.nn.Parameter]:
        return []

    def reset(self, seed: int) -> None:
        pass

    def store(self, t: int) -> None:
        pass

    def step(self, actions: np.ndarray, reward: np.ndarray, term: np.ndarray, trunc: np.ndarray) -> None:
        pass

    def flatten(self, mask: torch.Tensor) -> None:
        pass

    def loss(self, idx, logits, h, env_steps: int) -> tuple[torch.Tensor, dict[str, float]]:
        return torch.zeros(()), {}

    def state_dict(self) -> None:
        return None

    def load_state_dict(self, s: Any) -> None:
        pass

    def close(self) -> None:
        pass


class Parts(NamedTuple):
    """What the loop calls, each chosen from the recipe once."""

    #: The policy and value network.
    agent: ActorCritic
    #: One env's observation shape, and the element type the network takes (uint8 frames, float features).
    obs_shape: tuple[int, ...]
    obs_dtype: torch.dtype
    #: The observation normaliser (running statistics for features; disabled for frames, which the network scales).
    obs_norm: ObsNormalizer
    #: A raw observation batch as the network's input (normalised, updating the statistics; or the frames as they are).
    encode: Callable[[np.ndarray], torch.Tensor]
    #: What the update does to each minibatch of observations (a random shift, or nothing).
    augment: Callable[[torch.Tensor], torch.Tensor]
    #: Guidance from the game's features (:mod:`.guidance`), or :class:`Unguided`.
    guide: Any
    device: torch.device
    #: The network as the loop calls it: `act` in the rollout, `heads` in the update (eager, or compiled:
    #: :mod:`.compiled`).
    net: Network
    #: A self-supervised loss from the frames alone (:mod:`.selfsup`): `loss(frames, embedding)` per minibatch.
    frames_loss: Any
    #: An exploration bonus from the frames alone (:mod:`.novelty`): `bonus(t, h, raw, valid)` per env step, added to
    #: the scaled reward (or kept as a reward of its own), `advantages(batch, buf, next_obs)` after GAE (its own
    #: advantage joined to the game's), and `loss(frames, embedding, rows)` per minibatch.
    novelty: Any


def parts_of(recipe: Recipe, envs: VectorEnv, teacher: Any = None) -> Parts:
    """The parts of `recipe` for `envs` (its observations), the network built on the recipe's device. `ValueError`
    before anything is allocated when the network or the rollout would be too large. Consumes torch's random
    stream as the network's initialisation does, and nothing else (the auxiliary head draws from its own)."""
    obs_shape = tuple(envs.single_observation_space.shape or ())
    network = network_of(recipe)
    pixels = network != "mlp"
    device = torch.device(recipe.device)
    size = parameter_count(network, obs_shape, recipe.hidden) if pixels else 0
    if size > MAX_PARAMETERS:
        raise ValueError(
            f"the {network} network on observations of shape {obs_shape} would have {size:,} parameters, more than "
            f"{MAX_PARAMETERS:,}: smaller observations (obs_size), fewer stacked frames or a smaller network"
        )
    agent = build_agent(network, obs_shape, NUM_ACTIONS, recipe.hidden, recipe.invert_frames).to(device)
    guide: Any = Unguided()
    if recipe.aux_coef > 0 or teacher is not None:
        from .guidance import Guidance

        guide = Guidance(recipe, cast(CnnAgent, agent), teacher, recipe.num_steps, device)
    # Beside each step, guidance stores the twin's features (twice, with the batch) and the teacher's log-probabilities.
    n, t_len = recipe.num_envs, recipe.num_steps
    per_step = Rollout.bytes_per_step(obs_shape, pixels, 2 * guide.feat_dim + NUM_ACTIONS)
    if n * t_len * per_step > MAX_ROLLOUT_BYTES:
        guide.close()
        raise ValueError(
            f"invalid values {n} and {t_len} for options `num_envs` and `num_steps`: an update's rollout would take "
            f"{n * t_len * per_step / 2**30:.1f} GiB, more than {MAX_ROLLOUT_BYTES >> 30} GiB: fewer envs or steps"
        )
    # Vector observations are standardised with running statistics; frames are scaled by the network itself.
    obs_norm = ObsNormalizer(obs_shape, recipe.norm_obs and not pixels)

    def encode(raw: np.ndarray) -> torch.Tensor:
        """A batch of observations as the network takes them (frames stay uint8: a quarter of the memory)."""
        return torch.from_numpy(raw if pixels else obs_norm(raw, update=True)).to(device)

    obs_dtype = torch.uint8 if pixels else torch.float32
    augment = augmentation(recipe, obs_shape)
    net = network_for(recipe, agent)
    width = cast(CnnAgent, agent).embedding_width if pixels else 0
    return Parts(
        agent,
        obs_shape,
        obs_dtype,
        obs_norm,
        encode,
        augment,
        guide,
        device,
        net,
        frames_loss(recipe, width, obs_shape, device),
        novelty_of(recipe, obs_shape, device, agent),
    )
