"""The recipe's networks: an MLP actor and critic on features (:class:`Agent`), CNNs on frames with one trunk or two
(:class:`CnnAgent`), and :func:`build_agent`, which makes the one a recipe names. Orthogonal initialisation as in
CleanRL's PPO. Nothing here reads or writes files (:mod:`.modelfile` does) or knows of training."""

from __future__ import annotations

import math
from typing import TypeVar, cast

try:
    import torch
    import torch.nn.functional as F
    from torch import nn
except ImportError as err:  # pragma: no cover - exercised only without torch
    raise ImportError(
        "chopperscape.learn needs PyTorch: pip install 'chopperscape[train]' (the CPU build of torch is enough)"
    ) from err

from .. import NUM_ACTIONS
from .recipe import NETWORKS

#: A layer that `_layer` initialises.
_L = TypeVar("_L", nn.Linear, nn.Conv2d)


def _layer(layer: _L, std: float = math.sqrt(2)) -> _L:
    """Orthogonal weights and zero biases, as in CleanRL's PPO."""
    nn.init.orthogonal_(layer.weight, std)
    if layer.bias is not None:
        nn.init.constant_(layer.bias, 0.0)
    return layer


class ActorCritic(nn.Module):
    """What PPO needs of a network: `actor(obs)` gives the action logits and `critic(obs)` the value."""

    actor: nn.Module
    critic: nn.Module

    def value(self, x: torch.Tensor) -> torch.Tensor:
        return self.critic(x).squeeze(-1)

    def heads(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor | None]:
        """`(logits, value, embedding)`: the embedding is what both heads read where they share a trunk (a CNN's),
        for auxiliary losses on it; None for separate networks."""
        return self.actor(x), self.value(x), None

    def act(self, x: torch.Tensor, action: torch.Tensor | None = None):
        """`(action, log-probability, entropy, value)`; the action is sampled unless given."""
        return act_on(self.heads, x, action)[:4]


def act_on(heads, x: torch.Tensor, action: torch.Tensor | None = None):
    """:meth:`ActorCritic.act` through any `heads` function (the agent's own, or a compiled one), with the embedding
    the heads read: `(action, log-probability, entropy, value, embedding)`, the action sampled from torch's stream
    unless given (the embedding None for separate networks)."""
    logits, value, h = heads(x)
    dist = torch.distributions.Categorical(logits=logits)
    if action is None:
        action = dist.sample()
    return action, dist.log_prob(action), dist.entropy(), value, h


class Agent(ActorCritic):
    """Separate actor and critic MLPs (tanh), orthogonal init as in CleanRL's PPO."""

    def __init__(self, obs_dim: int, num_actions: int, hidden: int):
        super().__init__()
        self.critic = nn.Sequential(
            _layer(nn.Linear(obs_dim, hidden)),
            nn.Tanh(),
            _layer(nn.Linear(hidden, hidden)),
            nn.Tanh(),
            _layer(nn.Linear(hidden, 1), 1.0),
        )
        self.actor = nn.Sequential(
            _layer(nn.Linear(obs_dim, hidden)),
            nn.Tanh(),
            _layer(nn.Linear(hidden, hidden)),
            nn.Tanh(),
            _layer(nn.Linear(hidden, num_actions), 0.01),
        )


class Frames(nn.Module):
    """The env's grayscale observation as the convolutions want it: ``(N, H, W)`` or ``(N, H, W, k)`` (k stacked
    frames, uint8 or float in 0..255) to ``(N, k, H, W)`` floats in [0, 1]. Part of the network, so that a
    saved or exported policy takes the env's observation unchanged.

    With `invert`, the floats are ``1 - x / 255``: ChopperScape's sky is white, so plain scaling gives every input
    a large constant (1.0 nearly everywhere) on which the sprites are small dips. Through ReLU convolutions that
    constant dominates the trunk's output (measured at initialisation on random play: the embedding varies by 7 %
    of its mean across frames, and 38 % of its units never fire) and PPO's policy settles on one action. Inverted,
    the sky is 0 and the sprites and the gauge are positive, as on Atari's dark screens (ratio 44 %, 6 % dead).
    Models of chopperscape 0.1.0 read plain frames (`Recipe.invert_frames` is False for them)."""

    def __init__(self, invert: bool = False):
        super().__init__()
        self.invert = invert

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        # Permuted first, cast after: the floats come out channels-last in memory, which the CPU convolutions
        # read faster than a strided view of NHWC floats (and the same numbers).
        x = x.unsqueeze(1) if x.dim() == 3 else x.permute(0, 3, 1, 2)
        if self.invert:
            return 1.0 - x.float() * (1.0 / 255.0)
        return x.float() * (1.0 / 255.0)


#: CNN layouts: (channels, kernel, stride) per convolution, then the width of the dense layer. "small" on frames
#: under 64 pixels starts with a 4×4 stride-2 convolution, so that its second one sees the same 9×9 map at 42×42
#: as at 84×84.
CNNS = {
    "nature": ([(32, 8, 4), (64, 4, 2), (64, 3, 1)], 512),
    "small": ([(16, 8, 4), (32, 4, 2)], 256),
    "small-42": ([(16, 4, 2), (32, 4, 2)], 256),
}


class Coords(nn.Module):
    """CoordConv's coordinate channels (Liu et al. 2018) after a convolution without padding: the two channels a
    CoordConv appends to its input (each pixel's row and column, scaled to [-1, 1]) reach the convolution's output
    as a map linear in the output's row and column, so they are added there as ``a·row + b·col`` per channel with
    learned `a` and `b` (the constant part is the convolution's bias). The same numbers as the concatenation, with
    no batch-sized constant (the exported graph broadcasts two fixed maps)."""

    def __init__(self, channels: int, size: tuple[int, int]):
        super().__init__()
        h, w = size
        self.weight = nn.Parameter(torch.zeros(2, channels, 1, 1))
        self.register_buffer("rows", torch.linspace(-1.0, 1.0, h).view(1, 1, h, 1), persistent=False)
        self.register_buffer("cols", torch.linspace(-1.0, 1.0, w).view(1, 1, 1, w), persistent=False)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.weight[0] * self.get_buffer("rows") + self.weight[1] * self.get_buffer("cols")


class Stem(nn.Module):
    """Grey bands before the first convolution: each stacked frame's pixel `x` (inverted, in [0, 1]) becomes
    ``relu(x − knot)`` for each knot of :data:`STEM_KNOTS` (the knot 0 passes the frame through). The first
    convolution sums a patch of pixels before any nonlinearity, so a patch fully covered by a light sprite and one
    partly covered by a darker one can sum alike (the agent view's fuel tank and chopper at 42×42); with a ramp per
    band it weighs the bands apart, as MinAtar's one channel per kind of object lets it, from the frames' grey levels
    alone. Fixed, not learned: the convolution's weights on each band are what learns (and no gradient flows into
    the frames, so the stem costs one forward pass of a 1×1 convolution)."""

    def __init__(self, frames: int):
        super().__init__()
        k = len(STEM_KNOTS)
        self.frames = frames
        # A grouped 1×1 convolution with fixed weights 1 and biases −knot: frame f to channels f·k … f·k + k − 1
        # (what the exported graph takes: a Conv and a Relu).
        self.register_buffer("weight", torch.ones(frames * k, 1, 1, 1), persistent=False)
        self.register_buffer("bias", -torch.tensor(STEM_KNOTS).repeat(frames), persistent=False)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return torch.relu(F.conv2d(x, self.get_buffer("weight"), self.get_buffer("bias"), groups=self.frames))


#: Where the stem's ramps start, in inverted frames' units (sky 0, the agent view's tank 0.31, chopper 0.56,
#: bird 1): the frame itself, and ramps from between the sky and the tank and between the tank and the chopper.
STEM_KNOTS = (0.0, 0.2, 0.45)


class Keypoints(nn.Module):
    """A spatial soft-argmax (Levine et al. 2016): each feature map becomes the expected row and column of a
    softmax over its positions, a keypoint in [-1, 1]²: `C` maps of `H × W` give `2C` numbers that say where
    things are, in place of the flattened maps."""

    def __init__(self, size: tuple[int, int]):
        super().__init__()
        h, w = size
        rows = torch.linspace(-1.0, 1.0, h).view(h, 1).expand(h, w)
        cols = torch.linspace(-1.0, 1.0, w).view(1, w).expand(h, w)
        self.register_buffer("grid", torch.stack([rows, cols], -1).reshape(h * w, 2), persistent=False)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        p = torch.softmax(x.flatten(2), -1)  # (N, C, H·W)
        return (p @ self.get_buffer("grid")).flatten(1)  # (N, 2C)


#: What a CNN network's name may add to its base ("small", "nature"): "-split" gives the critic a trunk of its own,
#: "-coord" CoordConv's coordinates after the first convolution, "-keypoints" a spatial soft-argmax in place of the
#: flattened maps, "-deep" a second dense layer of the same width after the first, "-stem" a per-pixel stem before
#: the first convolution (:class:`Stem`), "-conv3" a third convolution (3×3, stride 1, as many maps as the second)
#: before the dense layers, "-norm" a LayerNorm after each dense layer, before its ReLU. The names `Recipe.network`
#: takes are in :data:`chopperscape.learn.recipe.NETWORKS`.
VARIANTS = ("-split", "-coord", "-keypoints", "-deep", "-stem", "-conv3", "-norm")


class CnnAgent(ActorCritic):
    """Actor and critic heads on one shared CNN trunk (the Atari PPO layout of CleanRL and SB3's CnnPolicy), or,
    for a "-split" network, each on a trunk of its own (the layout of PPG's separate value network, Cobbe et al.
    2021: the value loss no longer shapes the policy's features). "-coord" adds CoordConv's coordinates to the
    first convolution (:class:`Coords`), "-keypoints" reads the last maps as keypoints (:class:`Keypoints`), "-deep"
    adds a second dense layer (relative positions, such as the nearest tank's from the chopper, are a product of two
    positions: one ReLU layer after the maps gives the linear heads little to combine them with).
    "-stem" reads each pixel's grey band before the first convolution (:class:`Stem`), "-conv3" adds a third
    convolution (3×3, stride 1) and "-norm" a LayerNorm after each dense layer (issue 43's probes of both learned
    less per decision; docs/notes/pixels-speed-and-probes.md).
    `actor(obs)` gives the logits and `critic(obs)` the value, as for :class:`Agent`."""

    def __init__(self, obs_shape: tuple[int, ...], num_actions: int, network: str, invert_frames: bool = False):
        super().__init__()
        base, *variants = network.split("-")
        self.split = "split" in variants
        h, w = obs_shape[:2]
        stack = obs_shape[2] if len(obs_shape) == 3 else 1
        name = "small-42" if base == "small" and min(h, w) < 64 else base
        convs, width = CNNS[name]
        if "conv3" in variants:  # a third convolution on the second's maps: local mixes of where things are
            convs = [*convs, (convs[-1][0], 3, 1)]
        sizes = [(h, w)]
        for _, kernel, stride in convs:
            sizes.append(((sizes[-1][0] - kernel) // stride + 1, (sizes[-1][1] - kernel) // stride + 1))
            if min(sizes[-1]) < 1:
                raise ValueError(
                    f"frames of {h}×{w} are too small for the {base!r} network (at least 36×36 for 'nature', "
                    "16×16 for 'small')"
                )
        last = convs[-1][0]
        flat = 2 * last if "keypoints" in variants else last * sizes[-1][0] * sizes[-1][1]

        def make_trunk() -> nn.Sequential:
            layers: list[nn.Module] = [Frames(invert_frames)]
            channels = stack
            if "stem" in variants:
                layers.append(Stem(stack))
                channels = stack * len(STEM_KNOTS)
            for i, (out, kernel, stride) in enumerate(convs):
                layers.append(_layer(nn.Conv2d(channels, out, kernel, stride)))
                if i == 0 and "coord" in variants:
                    layers.append(Coords(out, sizes[1]))
                if i < len(convs) - 1 or "keypoints" not in variants:  # the soft-argmax reads the maps before ReLU
                    layers.append(nn.ReLU())
                channels = out
            read: nn.Module = Keypoints(sizes[-1]) if "keypoints" in variants else nn.Flatten()

            def dense(inputs: int) -> list[nn.Module]:  # with "-norm", a LayerNorm between the layer and its ReLU
                return [
                    _layer(nn.Linear(inputs, width)),
                    *([nn.LayerNorm(width)] if "norm" in variants else []),
                    nn.ReLU(),
                ]

            layers += [read, *dense(flat)]
            if "deep" in variants:  # a second dense layer: the heads read a nonlinear mix of where things are
                layers += dense(width)
            return nn.Sequential(*layers)

        trunk = make_trunk()
        # `actor.0` and `critic.0` are the one trunk (or the two); these names are the checkpoint format's.
        self.actor = nn.Sequential(trunk, _layer(nn.Linear(width, num_actions), 0.01))
        critic_trunk = make_trunk() if self.split else trunk  # a trunk of its own: its own initial weights
        self.critic = nn.Sequential(critic_trunk, _layer(nn.Linear(width, 1), 1.0))

    def heads(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor | None]:
        """`(logits, value, embedding)` from one pass of each trunk: with a shared trunk `actor(x)` and `critic(x)`
        would each run it (twice the convolutions, forward and backward, for the same numbers), so
        :meth:`ActorCritic.act` runs it once. The embedding is the actor's."""
        actor, critic = cast(nn.Sequential, self.actor), cast(nn.Sequential, self.critic)
        h = actor[0](x)
        value = critic[1](critic[0](x) if self.split else h)
        return actor[1](h), value.squeeze(-1), h

    @property
    def embedding_width(self) -> int:
        return int(cast(nn.Linear, cast(nn.Sequential, self.actor)[1]).in_features)


def build_agent(
    network: str,
    obs_shape: tuple[int, ...],
    num_actions: int = NUM_ACTIONS,
    hidden: int = 128,
    invert_frames: bool = False,
) -> ActorCritic:
    """The agent for `network` ("mlp", "small" or "nature") on observations of `obs_shape` (one env's); a CNN reads
    inverted frames with `invert_frames` (see :class:`Frames`)."""
    if network == "mlp":
        if len(obs_shape) != 1:
            raise ValueError(f"the mlp network takes vector observations (obs_type='features'), not shape {obs_shape}")
        return Agent(int(obs_shape[0]), num_actions, hidden)
    if network not in NETWORKS or network == "auto":
        raise ValueError(f"invalid network {network!r}: allowed {', '.join(map(repr, NETWORKS))}")
    if len(obs_shape) not in (2, 3):
        raise ValueError(f"the {network!r} CNN takes grayscale frames (obs_type='grayscale'), not shape {obs_shape}")
    return CnnAgent(tuple(obs_shape), num_actions, network, invert_frames)


def parameter_count(network: str, obs_shape: tuple[int, ...], hidden: int) -> int:
    """How many parameters the agent `network` on observations of `obs_shape` has, counted on the meta device (the
    shapes only, no memory): a CNN's size grows with its frames, so it is known before anything is allocated."""
    with torch.device("meta"):
        return sum(p.numel() for p in build_agent(network, obs_shape, NUM_ACTIONS, hidden).parameters())
