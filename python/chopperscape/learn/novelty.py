"""An exploration bonus from the frames alone, a part the training loop calls (`Recipe.rnd_coef`): Random Network
Distillation (Burda et al. 2019, "Exploration by Random Network Distillation"). A fixed, randomly initialised CNN
(the target) maps each frame to 128 numbers; a second CNN (the predictor) learns to match it on the frames the agent
sees. Where the agent has often been, the predictor is right; where it has seldom been, it is wrong, and its error
is the bonus added to the step's reward. Nothing privileged: the frames are the agent's own, as the policy sees
them.

Why here: issue 43's stalled seed 102 flies at the bottom of the sky, where tanks are born and rise away, while
every other seed flies at the top, where every tank comes to it (`python/examples/flight_probe.py`;
docs/notes/pixels-speed-and-probes.md, fifteenth session). Entropy spreads a policy where it is; a novelty bonus
pulls it toward the frames it has not seen, the ones at the other end of the sky.

As CleanRL's `ppo_rnd_envpool.py` does, save what the 2-core pixel loop asks: the latest frame of each stack, each pixel
standardised by running statistics and clipped to ±5 (with `rnd_pool` P, each P × P square of pixels averaged into one
first: at P = 2 a quarter of the pixels, a sixth of the networks' arithmetic, about half of the bonus's time); the error
(mean squared over the 128 outputs) divided by the running standard deviation of its discounted sum (γ 0.99, not cut at
episode ends); the predictor trained on every minibatch. By default one value head: the bonus, times `rnd_coef`, is
added to the step's scaled reward and cut at episode ends, so it also pays for surviving, wherever the chopper is. With
`rnd_own_value` (:class:`OwnValueDistillation`), the paper's two heads: the bonus is a reward of its own with a value
head of its own on the policy's trunk, its return not cut at episode ends (γ 0.99, the recipe's λ), and the policy
learns from the advantage ``A_game + rnd_coef · A_bonus`` (the paper's 2:1 is `rnd_coef` 0.5); its errors are taken
for the whole rollout in one pass once it ends (:meth:`OwnValueDistillation.settle`). With `rnd_floor` F below 1
the weight falls linearly over the step budget to F × `rnd_coef` (as `ent_floor` does the entropy's): a search early,
the game's return alone to learn from late; with `rnd_hold` H it holds at `rnd_coef` over the first H of the budget
and falls over the rest. Training only: neither network nor the bonus's value head is part of the
policy, the saved model or its export.

:func:`novelty_of` gives the part for a recipe: :class:`NoNovelty` (nothing, no state) when the weight is 0. The loop
calls `schedule(env_steps)` before each rollout, `bonus(t, h, raw, valid)` at each rollout step (`h`, the embedding
the policy acted on), `advantages(batch, buf, next_obs)` after GAE and `loss(x, h, idx)` on each minibatch.
"""

from __future__ import annotations

import math
from typing import Any, cast

import numpy as np
import torch
from torch import nn

from .normalize import RunningMeanStd
from .recipe import Recipe
from .rollout import Batch, Rollout

#: The discount of the bonus's running sum, the one its scale is taken from (the paper's γ_I).
GAMMA_INTRINSIC = 0.99
#: The width of the target's output.
OUTPUT_WIDTH = 128
#: The most frames the networks read in one call when the bonus's errors are taken a rollout at a time.
CHUNK = 2048


class NoNovelty:
    """No bonus: no parameters, no columns, no state."""

    @property
    def params(self) -> list[nn.Parameter]:
        return []

    def schedule(self, env_steps: int) -> None:
        pass

    def bonus(self, t: int, h: torch.Tensor | None, raw: np.ndarray, valid: np.ndarray) -> float:
        return 0.0

    def advantages(self, batch: Batch, buf: Rollout, next_obs: torch.Tensor) -> Batch:
        return batch

    def loss(self, x: torch.Tensor, h: torch.Tensor | None, idx: torch.Tensor) -> tuple[torch.Tensor, dict[str, float]]:
        return torch.zeros(()), {}

    def state_dict(self) -> None:
        return None

    def load_state_dict(self, s: Any) -> None:
        if s is not None:
            raise ValueError("it holds a novelty bonus's networks, and this recipe has none (rnd_coef 0)")


def _cnn(size: tuple[int, int], head: list[int]) -> nn.Sequential:
    """Two convolutions (16 maps 4×4 stride 2, 32 maps 4×4 stride 2, leaky ReLUs) on one frame, then dense layers
    of widths `head` (ReLUs between them)."""
    h, w = size
    for _ in range(2):
        h, w = (h - 4) // 2 + 1, (w - 4) // 2 + 1
    layers: list[nn.Module] = [nn.Conv2d(1, 16, 4, 2), nn.LeakyReLU(), nn.Conv2d(16, 32, 4, 2), nn.LeakyReLU()]
    layers.append(nn.Flatten())
    width = 32 * h * w
    for i, out in enumerate(head):
        if i:
            layers.append(nn.ReLU())
        layers.append(nn.Linear(width, out))
        width = out
    for m in layers:
        if isinstance(m, (nn.Conv2d, nn.Linear)):
            nn.init.orthogonal_(m.weight, math.sqrt(2))
            nn.init.zeros_(cast(torch.Tensor, m.bias))
    return nn.Sequential(*layers)


class RandomDistillation:
    """The bonus of a fixed random target and a predictor that learns it, on the latest frame of each stack."""

    #: Whether the bonus has a value head of its own (:class:`OwnValueDistillation`): a saved state must agree.
    own_value = False

    def __init__(
        self,
        coef: float,
        obs_shape: tuple[int, ...],
        num_envs: int,
        seed: int,
        device: Any,
        proportion: float = 1.0,
        pool: int = 1,
        floor: float = 1.0,
        total_steps: int = 1,
        hold: float = 0.0,
    ):
        h, w = obs_shape[0] // pool, obs_shape[1] // pool
        if min(h, w) < 10:
            pooled = f", {pool}×{pool} pixels averaged into one," if pool > 1 else ""
            raise ValueError(
                f"frames of {obs_shape[0]}×{obs_shape[1]}{pooled} are too small for the novelty bonus's networks "
                "(at least 10×10 after pooling)"
            )
        self.coef, self.device, self.proportion, self.pool = coef, device, proportion, pool
        self.floor, self.total_steps, self.hold = floor, total_steps, hold
        self.weight = coef  # the weight at the rollout under way (:meth:`schedule`)
        # Its own random stream: the networks are drawn inside a fork of torch's, so the policy's initialisation
        # and the action sampling stay what they are without the bonus.
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed + 0x52D)
            self.target = _cnn((h, w), [OUTPUT_WIDTH]).to(device)
            self.predictor = _cnn((h, w), [256, 256, OUTPUT_WIDTH]).to(device)
        self.target.requires_grad_(False)
        self.params = list(self.predictor.parameters())
        self.frames = RunningMeanStd((h, w))  # each (pooled) pixel's running mean and variance
        self.errors = RunningMeanStd(())  # of the bonus's discounted running sum
        self.running = np.zeros(num_envs)
        self.since = [0.0, 0]  # the raw errors' sum and count since the last update, for the progress columns
        self.reported = 0.0

    def _latest(self, x: torch.Tensor) -> torch.Tensor:
        """`(N, H / pool, W / pool)` float32: each stack's latest frame (uint8, ``(N, H, W)`` or ``(N, H, W, k)``),
        each `pool` × `pool` square of pixels averaged into one (exact: `pool` is 1, 2 or 4, a power of two), a
        remainder row or column dropped."""
        latest = (x if x.dim() == 3 else x[..., -1]).float()
        if self.pool > 1:
            latest = torch.nn.functional.avg_pool2d(latest.unsqueeze(1), self.pool).squeeze(1)
        return latest

    def _input(self, latest: torch.Tensor) -> torch.Tensor:
        """`(N, 1, H / pool, W / pool)`: the frames :meth:`_latest` gives, standardised by the running statistics and
        clipped to ±5."""
        mean = torch.as_tensor(self.frames.mean, dtype=torch.float32, device=latest.device)
        std = torch.as_tensor(np.sqrt(self.frames.var + 1e-8), dtype=torch.float32, device=latest.device)
        return ((latest - mean) / std).clamp(-5.0, 5.0).unsqueeze(1)

    def _frame_error(self, latest: torch.Tensor) -> torch.Tensor:
        """Each frame's error (of the frames :meth:`_latest` gives): the predictor's output against the target's,
        squared, averaged over the outputs."""
        return self._distance(self._input(latest))

    def _distance(self, seen: torch.Tensor) -> torch.Tensor:
        """Each input's error: the predictor's output against the target's, squared, averaged over the outputs."""
        return ((self.predictor(seen) - self.target(seen)) ** 2).mean(-1)

    def _error(self, x: torch.Tensor) -> torch.Tensor:
        """Each stack's error (uint8, ``(N, H, W)`` or ``(N, H, W, k)``): :meth:`_frame_error` of its latest frame."""
        return self._frame_error(self._latest(x))

    def _seen(self, raw: np.ndarray, valid: np.ndarray) -> torch.Tensor:
        """The networks' input for the observations `raw` a step returned (:meth:`_input`), the frame statistics first
        updated with the valid ones."""
        with torch.inference_mode():
            latest = self._latest(torch.from_numpy(raw).to(self.device))  # pooled once, for both
            if valid.any():  # bytes (or means of 4 or 16) are exact in float32, so as float64 they are as they were
                self.frames.update(latest[torch.from_numpy(valid).to(self.device)].double().cpu().numpy())
            return self._input(latest)

    def _errors(self, seen: torch.Tensor) -> np.ndarray:
        """Each input's error (:meth:`_distance`, as float64), in calls of at most :data:`CHUNK` frames."""
        with torch.inference_mode():
            return torch.cat([self._distance(c) for c in seen.split(CHUNK)]).double().cpu().numpy()

    def _scale(self, error: np.ndarray, valid: np.ndarray) -> np.ndarray:
        """The unweighted bonus (float64) of one rollout step's envs from their errors, 0 on reset steps; the running
        sums and the bonus's scale are updated with the valid ones."""
        self.running = np.where(valid, self.running * GAMMA_INTRINSIC + error, self.running)
        if valid.any():
            self.errors.update(self.running[valid])
            self.since = [self.since[0] + float(error[valid].sum()), self.since[1] + int(valid.sum())]
        return np.where(valid, error / math.sqrt(float(self.errors.var) + 1e-8), 0.0)

    def scaled(self, raw: np.ndarray, valid: np.ndarray) -> np.ndarray:
        """The unweighted bonus (float64) of each env's step that led to `raw` (the observations the step returned),
        0 on reset steps; the frame statistics and the bonus's scale are updated with the valid ones."""
        return self._scale(self._errors(self._seen(raw, valid)), valid)

    def schedule(self, env_steps: int) -> None:
        """Sets the weight of the rollout about to start, at `env_steps`: `coef` over the first `hold` of the step
        budget, then falling linearly over the rest to `floor` of itself (:func:`novelty_weight`). It follows env
        steps only, so a resumed run and a busy host weigh the bonus as the uninterrupted run does."""
        self.weight = novelty_weight(self.coef, self.floor, env_steps, self.total_steps, self.hold)

    def bonus(self, t: int, h: torch.Tensor | None, raw: np.ndarray, valid: np.ndarray) -> np.ndarray:
        """The weighted bonus of rollout step `t`'s envs (:meth:`scaled` times the weight), added to their reward;
        `raw` are the observations the step returned (`h`, the embedding the policy acted on, is the own value's)."""
        return (self.weight * self.scaled(raw, valid)).astype(np.float32)  # as in runs before `scaled` was split out

    def advantages(self, batch: Batch, buf: Rollout, next_obs: torch.Tensor) -> Batch:
        """The batch as it is: the bonus is already in the rewards its advantages come from."""
        return batch

    def loss(self, x: torch.Tensor, h: torch.Tensor | None, idx: torch.Tensor) -> tuple[torch.Tensor, dict[str, float]]:
        """The predictor's loss on a minibatch `x` (the target fixed), unweighted: it trains only the predictor, whose
        parameters nothing else reads (`h` and `idx`, the minibatch's embedding and rows, are the own value's), on
        the first `proportion` of the minibatch's rows (a random share: the rows are a permutation's). The columns add
        `novelty`, the mean raw error of the valid steps of the rollout this update learns from."""
        if self.since[1]:  # the update's first minibatch: the rollout's steps are all in
            self.reported, self.since = self.since[0] / self.since[1], [0.0, 0]
        err = self._error(x[: max(1, round(len(x) * self.proportion))]).mean()
        return err, {"rnd_loss": err.item(), "novelty": self.reported}

    def state_dict(self) -> dict[str, Any]:
        return {
            "target": {k: v.detach().cpu() for k, v in self.target.state_dict().items()},
            "predictor": {k: v.detach().cpu() for k, v in self.predictor.state_dict().items()},
            "frames": self.frames.state(),
            "errors": self.errors.state(),
            "running": self.running.tolist(),
        }

    def load_state_dict(self, s: Any) -> None:
        if not isinstance(s, dict):
            raise ValueError("it holds no novelty bonus's networks, and this recipe has one (rnd_coef > 0)")
        if ("value_head" in s) != self.own_value:
            has = "has a" if "value_head" in s else "has no"
            raise ValueError(
                f"its novelty bonus {has} value head of its own, and this recipe's differs (rnd_own_value)"
            )
        running = np.asarray(s["running"], dtype=np.float64)
        if running.shape != self.running.shape:
            raise ValueError(
                f"the novelty bonus's sums of {running.shape} envs, where the run has {self.running.shape}"
            )
        self.target.load_state_dict(s["target"])
        self.predictor.load_state_dict(s["predictor"])
        self.frames, self.errors = RunningMeanStd.from_state(s["frames"]), RunningMeanStd.from_state(s["errors"])
        self.running = running


class OwnValueDistillation(RandomDistillation):
    """The bonus as the paper has it: a reward of its own, learned by a value head of its own on the policy's trunk,
    its return not cut at episode ends, joined to the game's advantage after GAE."""

    own_value = True

    def __init__(self, recipe: Recipe, obs_shape: tuple[int, ...], agent: Any, device: Any):
        super().__init__(*_settings(recipe, obs_shape, device))
        with torch.random.fork_rng(devices=[]):  # its own stream, as the networks'
            torch.manual_seed(recipe.seed + 0x52E)
            self.value_head = nn.Linear(agent.embedding_width, 1).to(device)
            nn.init.orthogonal_(self.value_head.weight, 1.0)  # as the critic's
            nn.init.zeros_(self.value_head.bias)
        self.params = self.params + list(self.value_head.parameters())
        self.agent, self.gae_lambda, self.vf_coef = agent, recipe.gae_lambda, recipe.vf_coef
        self.rewards = torch.zeros((recipe.num_steps, recipe.num_envs), device=device)
        self.values = torch.zeros((recipe.num_steps, recipe.num_envs), device=device)  # the head's, at the rollout
        self.returns = torch.zeros(0, device=device)
        frame = self.frames.mean.shape  # the pooled frame's (H, W)
        self.seen = torch.zeros((recipe.num_steps, recipe.num_envs, 1, *frame), device=device)  # each step's input
        self.valid = np.zeros((recipe.num_steps, recipe.num_envs), bool)
        self.pending = 0  # the steps kept in `seen` whose bonus is not yet in `rewards`

    @torch.no_grad()
    def bonus(self, t: int, h: torch.Tensor | None, raw: np.ndarray, valid: np.ndarray) -> np.ndarray:
        """Keeps what rollout step `t`'s bonus needs: the networks' input from `raw` (:meth:`_seen`, the frame
        statistics updated step by step) and `valid`, and the bonus's value of the observation the policy acted on
        (read from `h`, the embedding its forward pass gave: no second pass over the rollout); the game's reward gets
        nothing added. The bonus itself, a reward of its own, is taken for the whole rollout at once (:meth:`settle`):
        the predictor does not change during a rollout, and one call over its frames costs less than a call a step."""
        self.values[t] = self.value_head(cast(torch.Tensor, h)).squeeze(-1)
        self.seen[t], self.valid[t], self.pending = self._seen(raw, valid), valid, t + 1
        return np.zeros(len(valid), np.float32)

    def settle(self) -> None:
        """The bonus of each rollout step kept since the last call, as a reward of its own (`rewards`): the errors of
        all their frames in one pass, then each step's scale in order, as step-by-step calls give it (the errors
        equal to float32 rounding, which a call's batch size can move)."""
        if self.pending:
            seen = self.seen[: self.pending]
            errors = self._errors(seen.reshape(-1, *seen.shape[2:])).reshape(self.pending, -1)
            for t in range(self.pending):
                bonus = self._scale(errors[t], self.valid[t]).astype(np.float32)
                self.rewards[t] = torch.from_numpy(bonus).to(self.device)
            self.pending = 0

    @torch.no_grad()
    def advantages(self, batch: Batch, buf: Rollout, next_obs: torch.Tensor) -> Batch:
        """The batch with the weight (``rnd_coef``, less with `rnd_floor`) times the bonus's advantage added to the
        game's: GAE over the rollout's valid steps with γ 0.99 and the recipe's λ, bootstrapped from `next_obs`, not
        cut at episode ends (a reset step carries nothing: the step that ended an episode bootstraps from the next
        episode's first). The bonus's returns, the value head's targets, are kept for :meth:`loss`."""
        self.settle()
        t_len, n = self.rewards.shape
        values = self.values  # the head's at each step, stored by `bonus` from the rollout's own pass
        next_value = self.value_head(self.agent.heads(next_obs)[2]).squeeze(-1)
        last = torch.zeros(n, device=self.device)
        adv = torch.zeros((t_len, n), device=self.device)
        for t in reversed(range(t_len)):
            valid = buf.valid[t].bool()
            step = self.rewards[t] + GAMMA_INTRINSIC * next_value - values[t]
            step = step + GAMMA_INTRINSIC * self.gae_lambda * last
            last = torch.where(valid, step, last)
            next_value = torch.where(valid, values[t], next_value)
            adv[t] = torch.where(valid, step, 0.0)
        mask = batch.mask
        own = adv.reshape(-1)[mask]
        self.returns = own + values.reshape(-1)[mask]
        return batch._replace(advantages=batch.advantages + self.weight * own)

    def loss(self, x: torch.Tensor, h: torch.Tensor | None, idx: torch.Tensor) -> tuple[torch.Tensor, dict[str, float]]:
        """The predictor's loss (:meth:`RandomDistillation.loss`) plus the bonus's value loss on the minibatch's
        embedding `h` (rows `idx` of the batch), weighted as the game's value loss is (`vf_coef`)."""
        predictor, row = super().loss(x, h, idx)
        value = self.value_head(cast(torch.Tensor, h)).squeeze(-1)
        return predictor + self.vf_coef * 0.5 * ((value - self.returns[idx]) ** 2).mean(), row

    def state_dict(self) -> dict[str, Any]:
        head = {k: v.detach().cpu() for k, v in self.value_head.state_dict().items()}
        return {**super().state_dict(), "value_head": head}

    def load_state_dict(self, s: Any) -> None:
        super().load_state_dict(s)
        self.value_head.load_state_dict(s["value_head"])


def novelty_of(recipe: Recipe, obs_shape: tuple[int, ...], device: Any, agent: Any = None) -> Any:
    """The exploration part `recipe` asks for: :class:`RandomDistillation` when `rnd_coef` > 0 (a CNN recipe:
    :func:`~.recipe.check_recipe` refuses it for features), :class:`OwnValueDistillation` with `rnd_own_value`
    (its value head reads the embedding of `agent`, a CNN agent), else :class:`NoNovelty`."""
    if recipe.rnd_coef <= 0:
        return NoNovelty()
    if recipe.rnd_own_value:
        return OwnValueDistillation(recipe, obs_shape, agent, device)
    return RandomDistillation(*_settings(recipe, obs_shape, device))


def _settings(recipe: Recipe, obs_shape: tuple[int, ...], device: Any) -> tuple[Any, ...]:
    """:class:`RandomDistillation`'s arguments from `recipe`, in its order (both kinds of bonus take them)."""
    return (
        recipe.rnd_coef,
        obs_shape,
        recipe.num_envs,
        recipe.seed,
        device,
        recipe.rnd_proportion,
        recipe.rnd_pool,
        recipe.rnd_floor,
        recipe.total_steps,
        recipe.rnd_hold,
    )


def novelty_weight(coef: float, floor: float, env_steps: int, total_steps: int, hold: float = 0.0) -> float:
    """The bonus's weight at `env_steps`: `coef` over the first `hold` of `total_steps`, then falling linearly over
    the rest to `floor` of itself, as :func:`~.ppo.entropy_coef` does the entropy's over the whole; `coef` exactly at
    the default floor of 1 (the runs before it), and the whole budget's fall exactly at the default hold of 0."""
    done = min(max((env_steps / total_steps - hold) / (1.0 - hold), 0.0), 1.0)
    return coef * (1.0 - (1.0 - floor) * done)
