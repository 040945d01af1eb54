"""A self-supervised loss from the frames alone, a part the training loop calls on every minibatch
(`Recipe.recon_coef`): a linear decoder reconstructs the latest frame, at half size, from the trunk's embedding
(the autoencoder loss of SAC+AE, Yarats et al. 2021, here beside PPO's). Nothing privileged: the target is the
minibatch's own input, as the network saw it (augmented, inverted), so the loss asks the trunk to keep where the
sprites are. Training only: the decoder is not part of the policy, the saved model or its export. Probed on the
pixel candidate (docs/notes/pixels-speed-and-probes.md, sixth session): the trunk then carries the fuel gauge as a
linear read-out (R² 0.99 against 0.63–0.68) and the birds' places twice as well, and the agent learns no more per
decision; an option, off in every preset.

:func:`frames_loss` gives the part for a recipe: :class:`NoFramesLoss` (nothing, no state) when the weight is 0.
"""

from __future__ import annotations

from typing import Any

try:
    import torch
    from torch import nn
    from torch.nn import functional
except ImportError as err:  # pragma: no cover - exercised only without torch
    raise ImportError(
        "chopperscape.learn needs PyTorch: pip install 'chopperscape[train]' (the CPU build of torch is enough)"
    ) from err

from .networks import Frames
from .recipe import Recipe


class NoFramesLoss:
    """No self-supervised loss: no parameters, no columns, no state."""

    @property
    def params(self) -> list[nn.Parameter]:
        return []

    def loss(self, x: torch.Tensor, h: torch.Tensor | None) -> tuple[torch.Tensor, dict[str, float]]:
        return torch.zeros(()), {}

    def state_dict(self) -> None:
        return None

    def load_state_dict(self, s: Any) -> None:
        if s is not None:
            raise ValueError("it holds a reconstruction decoder, and this recipe has none (recon_coef 0)")


class Reconstruction:
    """The latest frame of each stack, scaled as the network reads it and averaged over 2×2 blocks, predicted by a
    linear decoder from the embedding; the loss is `coef` × the mean squared error per pixel."""

    def __init__(self, coef: float, embedding_width: int, obs_shape: tuple[int, ...], invert: bool, device: Any):
        h, w = obs_shape[:2]
        self.coef = coef
        self.frames = Frames(invert)  # the network's own reading of a frame
        self.size = (h // 2, w // 2)
        # Its own random stream: the decoder is made uninitialised (`skip_init` draws nothing) and filled from a
        # generator of its own, so torch's stream (the network's, the sampling's) stays as it is.
        gen = torch.Generator().manual_seed(0x5EC0)
        self.decoder = nn.utils.skip_init(nn.Linear, embedding_width, self.size[0] * self.size[1])
        with torch.no_grad():
            bound = embedding_width**-0.5
            self.decoder.weight.uniform_(-bound, bound, generator=gen)
            self.decoder.bias.zero_()
        self.decoder.to(device)
        self.params = list(self.decoder.parameters())

    def target(self, x: torch.Tensor) -> torch.Tensor:
        """`(N, H/2 · W/2)`: each stack's latest frame (uint8, ``(N, H, W)`` or ``(N, H, W, k)``) in [0, 1], inverted
        as the network reads it, averaged over 2×2 blocks (an odd last row or column left out)."""
        latest = self.frames(x if x.dim() == 3 else x[..., -1:])  # (N, 1, H, W): only the latest frame converted
        return functional.avg_pool2d(latest, 2).flatten(1)

    def loss(self, x: torch.Tensor, h: torch.Tensor | None) -> tuple[torch.Tensor, dict[str, float]]:
        if h is None:
            raise ValueError("the reconstruction loss needs the network's embedding")
        err = ((self.decoder(h) - self.target(x)) ** 2).mean()
        return self.coef * err, {"recon_loss": err.item()}

    def state_dict(self) -> dict[str, torch.Tensor]:
        return {k: v.detach().cpu() for k, v in self.decoder.state_dict().items()}

    def load_state_dict(self, s: Any) -> None:
        if not isinstance(s, dict):
            raise ValueError("it holds no reconstruction decoder, and this recipe has one (recon_coef > 0)")
        self.decoder.load_state_dict(s)


def frames_loss(recipe: Recipe, embedding_width: int, obs_shape: tuple[int, ...], device: Any) -> Any:
    """The self-supervised part `recipe` asks for: :class:`Reconstruction` when `recon_coef` > 0 (a CNN recipe:
    :func:`~.recipe.check_recipe` refuses it for features), else :class:`NoFramesLoss`."""
    if recipe.recon_coef <= 0:
        return NoFramesLoss()
    return Reconstruction(recipe.recon_coef, embedding_width, obs_shape, recipe.invert_frames, device)
