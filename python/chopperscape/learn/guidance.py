"""Guidance from the game's features for pixel recipes: a part that plugs into the PPO loop of
:func:`chopperscape.learn.train.train` (`aux_coef > 0` or `teacher`), and is absent from plain PPO.

A twin env with `features` observations, reset with the same seeds and stepped with the same actions, is in the same
state at every step (determinism). A linear head on the CNN's trunk learns to predict its standardised features
(`aux_coef`); a features teacher reads them and the policy is pulled toward the teacher's action probabilities
(`teacher`, "kickstarting"). Only training sees either: the saved model is a pixel model. Privileged state: a
recipe that uses this does not learn from frames alone (docs/notes/inverted-frames-and-teacher.md).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from .. import NUM_ACTIONS, _core
from ..options import RULE_OPTIONS
from ..vector import VectorEnv
from .modelfile import Model, load
from .networks import CnnAgent
from .normalize import ObsNormalizer
from .recipe import Recipe
from .state import EnvBatch


def _rules(options: dict) -> dict:
    """The rules options among env `options`, as comparable values (numbers as floats), those equal to their default
    left out: `{}`, `{"frame_skip": 1}` and `{"alien_prob": 0.0}` are the same rules."""

    def value(v: object) -> object:
        try:
            return float(v) if not isinstance(v, bool) else str(v).lower()  # type: ignore[arg-type]
        except (TypeError, ValueError):
            return str(v).lower()

    defaults = {o["name"]: value(o["default"]) for o in _core.OPTIONS}
    return {k: value(v) for k, v in options.items() if k in RULE_OPTIONS and value(v) != defaults[k]}


def load_teacher(recipe: Recipe) -> Model:
    """The features model `recipe.teacher` names, checked to guide this recipe: a features MLP trained on the same
    rules (frame skip included). `ValueError` in one line otherwise; the file is read as data
    (`torch.load(weights_only=True)`), never run."""
    if not os.path.lexists(recipe.teacher):
        raise ValueError(f"teacher {recipe.teacher!r}: no such file (give a features model.pt from this trainer)")
    teacher = load(Path(recipe.teacher), f"teacher {recipe.teacher!r}")
    if teacher.recipe["obs_type"] != "features" or len(teacher.obs_shape) != 1:
        raise ValueError(
            f"teacher {recipe.teacher!r} learned {teacher.recipe['obs_type']!r} observations: a teacher must be a "
            "features model (--obs-type features)"
        )
    mine, theirs = _rules(recipe.env_options), _rules(teacher.recipe.get("env_options", {}))
    if mine != theirs:
        raise ValueError(
            f"teacher {recipe.teacher!r} learned other rules ({theirs or 'the defaults'}) than this run's "
            f"({mine or 'the defaults'}): train the teacher with the same rules options, frame_skip included"
        )
    return teacher


class Guidance:
    """The twin env, the auxiliary head and the teacher of one run, with their rollout buffers.

    The loop calls :meth:`reset` with the envs, :meth:`store` before each env step, :meth:`step` after it with the
    same actions, :meth:`flatten` once per update and :meth:`loss` per minibatch; :meth:`close` at the end. The
    same calls on :class:`~.parts.Unguided` do nothing: plain PPO's loop is this one."""

    def __init__(self, recipe: Recipe, agent: CnnAgent, teacher: Model | None, t_len: int, device: torch.device):
        self.recipe, self.teacher, self.device = recipe, teacher, device
        n = recipe.num_envs
        twin_options = {k: v for k, v in recipe.env_options.items() if k in RULE_OPTIONS}
        if teacher is not None:  # the teacher's own observation settings (a frame-stacked teacher, say)
            seen = teacher.recipe.get("env_options", {}).items()
            twin_options.update({k: v for k, v in seen if k not in RULE_OPTIONS and k != "obs_type"})
        self.twin = VectorEnv(n, num_threads=recipe.env_threads, obs_type="features", **twin_options)
        self.feat_dim = int((self.twin.single_observation_space.shape or (0,))[0])
        if teacher is not None and tuple(teacher.obs_shape) != (self.feat_dim,):
            self.twin.close()
            raise ValueError(
                f"teacher {recipe.teacher!r} takes observations of shape {teacher.obs_shape}, but its env options "
                f"give ({self.feat_dim},): it is not a model this trainer wrote"
            )
        self.aux_head: nn.Linear | None = None
        self.feat_norm: ObsNormalizer | None = None
        if recipe.aux_coef > 0:
            self.feat_norm = ObsNormalizer((self.feat_dim,), True)
            with torch.random.fork_rng(devices=[]):  # the head's init leaves the run's random stream as it was
                torch.manual_seed(recipe.seed + 1)
                self.aux_head = nn.Linear(agent.embedding_width, self.feat_dim).to(device)
        if teacher is not None:
            teacher.agent.to(device)
        aux = self.aux_head is not None
        self.buf_feat = torch.zeros((t_len, n, self.feat_dim) if aux else (0,), device=device)
        # The teacher's log-probabilities of the five actions in each stored state.
        self.buf_teach = torch.zeros((t_len, n, NUM_ACTIONS) if teacher is not None else (0,), device=device)
        self.next_feat = self.next_teach = torch.zeros(0)
        self.b_feat: torch.Tensor | None = None
        self.b_teach: torch.Tensor | None = None

    @property
    def params(self) -> list[nn.Parameter]:
        """The trainable parameters it adds (the auxiliary head's)."""
        return list(self.aux_head.parameters()) if self.aux_head is not None else []

    def _targets(self, feat_raw: np.ndarray) -> None:
        """The twin's features as the auxiliary head's target (standardised by running statistics) and the
        teacher's log-probabilities on them (its own frozen statistics)."""
        norm = self.feat_norm
        self.next_feat = torch.from_numpy(norm(feat_raw, update=True)).to(self.device) if norm else torch.zeros(0)
        if self.teacher is not None:
            with torch.no_grad():
                x = torch.from_numpy(self.teacher.norm(feat_raw)).to(self.device)
                self.next_teach = torch.log_softmax(self.teacher.agent.actor(x), -1)

    def reset(self, seed: int) -> None:
        feat_raw, _ = self.twin.reset(seed=seed)
        self._targets(feat_raw)

    def store(self, t: int) -> None:
        if self.aux_head is not None:
            self.buf_feat[t] = self.next_feat
        if self.teacher is not None:
            self.buf_teach[t] = self.next_teach

    def step(self, actions: np.ndarray, reward: np.ndarray, term: np.ndarray, trunc: np.ndarray) -> None:
        feat_raw, reward2, term2, trunc2, _ = self.twin.step(actions)
        if not all(map(np.array_equal, (reward, term, trunc), (reward2, term2, trunc2))):
            raise RuntimeError("the features twin env left the pixel env's game (rewards or ends differ)")
        self._targets(feat_raw)

    def flatten(self, mask: torch.Tensor) -> None:
        """The update's batch of stored targets, over the valid steps `mask`."""
        self.b_feat = self.buf_feat.reshape(-1, self.feat_dim)[mask] if self.aux_head is not None else None
        self.b_teach = self.buf_teach.reshape(-1, NUM_ACTIONS)[mask] if self.teacher is not None else None

    def loss(
        self, idx: torch.Tensor, logits: torch.Tensor, h: torch.Tensor | None, env_steps: int
    ) -> tuple[torch.Tensor, dict[str, float]]:
        """The minibatch `idx`'s added loss, and by name the parts it holds that this run logs (`aux_loss`, and
        `teacher_kl`, KL(teacher ‖ policy)). The teacher's weight falls linearly to 0 at `teacher_fade` ×
        `total_steps` (env steps, as every schedule)."""
        r = self.recipe
        zero = torch.zeros((), device=self.device)
        aux_loss = teacher_kl = zero
        if self.aux_head is not None and self.b_feat is not None and h is not None:
            aux_loss = ((self.aux_head(h) - self.b_feat[idx]) ** 2).mean()
        if self.b_teach is not None:
            t_logp = self.b_teach[idx]
            teacher_kl = (t_logp.exp() * (t_logp - torch.log_softmax(logits, -1))).sum(-1).mean()
        teach_w = r.teacher_coef * max(1.0 - env_steps / (r.teacher_fade * r.total_steps), 0.0)
        loss = r.aux_coef * aux_loss + (teach_w * teacher_kl if teach_w > 0 else zero)
        logged = {"aux_loss": aux_loss.item()} if self.aux_head is not None else {}
        if self.teacher is not None:
            logged["teacher_kl"] = teacher_kl.item()
        return loss, logged

    def state_dict(self) -> dict[str, Any]:
        """What `--resume` needs to continue it: the twin's state, the targets' statistics and the next targets."""
        out: dict[str, Any] = {
            "twin": EnvBatch(self.twin).state_dict(),
            "next_feat": self.next_feat,
            "next_teach": self.next_teach,
        }
        if self.feat_norm is not None:
            out["feat_rms"] = self.feat_norm.rms.state()
        if self.aux_head is not None:
            out["aux_head"] = self.aux_head.state_dict()
        return out

    def load_state_dict(self, s: dict[str, Any]) -> None:
        EnvBatch(self.twin).load_state_dict(s["twin"])
        self.next_feat, self.next_teach = s["next_feat"].to(self.device), s["next_teach"].to(self.device)
        if self.feat_norm is not None:
            self.feat_norm.rms = type(self.feat_norm.rms).from_state(s["feat_rms"])
        if self.aux_head is not None:
            self.aux_head.load_state_dict(s["aux_head"])

    def close(self) -> None:
        self.twin.close()
