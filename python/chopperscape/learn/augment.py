"""Data augmentation of the update's minibatches of frames: DrQ's and RAD's random shift (Kostrikov et al. 2020,
Laskin et al. 2020), and :func:`augmentation`, which turns a recipe's `augment` into the function the loop applies to
every minibatch (the identity for "none")."""

from __future__ import annotations

from collections.abc import Callable

try:
    import torch
except ImportError as err:  # pragma: no cover - exercised only without torch
    raise ImportError(
        "chopperscape.learn needs PyTorch: pip install 'chopperscape[train]' (the CPU build of torch is enough)"
    ) from err

from .recipe import Recipe


def shift_pad(obs_shape: tuple[int, ...]) -> int:
    """The random shift's padding for frames of `obs_shape`: 4 pixels at 84 × 84 (DrQ's), scaled, at least 1."""
    return max(1, round(4 * min(obs_shape[:2]) / 84))


def random_shift(x: torch.Tensor, pad: int, generator: torch.Generator | None = None) -> torch.Tensor:
    """DrQ's random shift of a batch of frame stacks `x` (``(N, H, W)`` or ``(N, H, W, k)``, any dtype): each
    padded by `pad` pixels that repeat its edges, then cropped back to ``H × W`` at its own random offset in
    ``0..=2·pad`` (integer shifts, one per frame stack, the same for its `k` frames)."""
    squeeze = x.dim() == 3
    if squeeze:
        x = x.unsqueeze(-1)
    n, h, w, _ = x.shape
    off = torch.randint(0, 2 * pad + 1, (2, n), device=x.device, generator=generator)
    # Edge padding as clamped indices: row r of the padded frame is row clamp(r - pad) of the frame.
    r = (torch.arange(h, device=x.device)[None, :] + off[0][:, None] - pad).clamp_(0, h - 1)
    c = (torch.arange(w, device=x.device)[None, :] + off[1][:, None] - pad).clamp_(0, w - 1)
    out = x[torch.arange(n, device=x.device)[:, None, None], r[:, :, None], c[:, None, :]]
    return out.squeeze(-1) if squeeze else out


def augmentation(recipe: Recipe, obs_shape: tuple[int, ...]) -> Callable[[torch.Tensor], torch.Tensor]:
    """What the update does to each minibatch of observations under `recipe.augment`: the random shift for "shift"
    (padding scaled to the frames, :func:`shift_pad`), else the identity. The rollout's forward passes see the
    observations as they are."""
    if recipe.augment != "shift":
        return _unchanged
    pad = shift_pad(obs_shape)
    return lambda x: random_shift(x, pad)


def _unchanged(x: torch.Tensor) -> torch.Tensor:
    return x
