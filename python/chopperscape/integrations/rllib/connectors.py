"""RLlib connectors and a learner for ChopperScape: pixels as floats for RLlib's default CNN (:class:`FloatPixels`),
and rewards scaled by the running std of the discounted return before GAE (:class:`ReturnScaling`,
:class:`ReturnScaledPPOLearner`), as the single-machine recipe, Gymnasium's `NormalizeReward` and SB3's
`VecNormalize` do. Re-exported by :mod:`chopperscape.integrations.rllib`."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.wrappers.utils import RunningMeanStd
from ray.rllib.algorithms.ppo.torch.ppo_torch_learner import PPOTorchLearner
from ray.rllib.connectors.connector_v2 import ConnectorV2
from ray.rllib.connectors.env_to_module.observation_preprocessor import SingleAgentObservationPreprocessor
from ray.rllib.connectors.learner import GeneralAdvantageEstimation
from ray.rllib.core.columns import Columns


class FloatPixels(SingleAgentObservationPreprocessor):
    """Pixel observations (`rgb`, `grayscale`, stacked or not: `uint8`) as `float32` in [0, 1], with a channel axis
    for plain grayscale: what RLlib's default CNN takes (it neither casts `uint8` nor reads 2-D boxes). Use it as
    `config.env_runners(env_to_module_connector=lambda env, spaces, device: FloatPixels())`."""

    def recompute_output_observation_space(self, input_observation_space, input_action_space):
        shape = tuple(input_observation_space.shape)
        return gym.spaces.Box(0.0, 1.0, shape + (1,) if len(shape) == 2 else shape, np.float32)

    def preprocess(self, observation, episode):
        return float_pixels(observation, np.ndim(observation))


def float_pixels(obs: Any, frame_ndim: int) -> np.ndarray:
    """What :class:`FloatPixels` makes of pixel observations, for one observation or a batch of them: `float32` in
    [0, 1] (from `uint8`), with a channel axis when one observation is a plain grayscale frame (`frame_ndim` 2)."""
    obs = np.asarray(obs)
    obs = obs.astype(np.float32) / 255.0 if obs.dtype == np.uint8 else obs.astype(np.float32, copy=False)
    return obs[..., None] if frame_ndim == 2 else obs


class ReturnScaling(ConnectorV2):
    """A learner connector that divides rewards by the running standard deviation of the discounted return, before
    GAE: what the single-machine recipe (:mod:`chopperscape.learn.train`), Gymnasium's `NormalizeReward` and SB3's
    `VecNormalize` do, and what RLlib's new API stack lacks. The statistics are Gymnasium's `RunningMeanStd`,
    updated from each batch's moments, and travel with the learner's state (checkpoints). The episode returns the
    env runners report stay the game's own: only what the learner sees is scaled.

    As in `NormalizeReward`, the discounted return runs over the whole episode, not over the chunk of it that one
    batch holds: a chunk that does not end its episode leaves its return to the episode's next chunk (`carry`, by
    episode id). With batches of 128 steps and γ 0.998 a chunk is a quarter of the return's horizon, so returns
    restarted at each chunk would spread less and scale the rewards up more. RLlib's bootstrap
    step (`Columns.LOSS_MASK` false) neither adds to the return nor to the statistics.

    A batch whose rows are not one per episode step (padded for a recurrent module) is left as it is."""

    def __init__(
        self, input_observation_space: Any = None, input_action_space: Any = None, *, gamma: float = 0.99, **kwargs: Any
    ) -> None:
        super().__init__(input_observation_space, input_action_space, **kwargs)
        self.gamma = float(gamma)
        self.rms = RunningMeanStd(shape=())
        #: The discounted return so far of each episode a batch left unfinished, by episode id.
        self.carry: dict[str, float] = {}

    def __call__(self, *, rl_module: Any, batch: dict[str, Any], episodes: Any, **kwargs: Any) -> Any:
        chunks = list(self.single_agent_episode_iterator(episodes, agents_that_stepped_only=False))
        lens = [len(e) for e in chunks]
        ids = [episode_id(e.id_) for e in chunks]
        for module_batch in batch.values():
            rewards = module_batch[Columns.REWARDS]
            r = _numpy(rewards).astype(np.float64)
            if r.shape[0] != sum(lens):
                continue
            mask = module_batch.get(Columns.LOSS_MASK)
            real = np.ones(r.shape[0], bool) if mask is None else _numpy(mask).astype(bool).reshape(-1)
            returns = discounted_returns(r, lens, self.gamma, [self.carry.get(i, 0.0) for i in ids], real)
            if real.any():
                self.rms.update(returns[real])
            carry, end = {}, 0
            for chunk, i, n in zip(chunks, ids, lens):
                end += n
                steps = np.flatnonzero(real[end - n : end])
                if not chunk.is_terminated and steps.size:
                    carry[i] = float(returns[end - n + steps[-1]])
            self.carry = carry
            module_batch[Columns.REWARDS] = rewards * (1.0 / np.sqrt(self.rms.var + 1e-8))
        return batch

    def get_state(self, components: Any = None, *, not_components: Any = None, **kwargs: Any) -> dict[str, Any]:
        return {
            "mean": float(self.rms.mean),
            "var": float(self.rms.var),
            "count": float(self.rms.count),
            "carry": dict(self.carry),
        }

    def set_state(self, state: dict[str, Any]) -> None:
        self.rms.mean = np.asarray(state["mean"], np.float64)
        self.rms.var = np.asarray(state["var"], np.float64)
        self.rms.count = float(state["count"])
        self.carry = {str(k): float(v) for k, v in state.get("carry", {}).items()}


def _numpy(x: Any) -> np.ndarray:
    return x.detach().cpu().numpy() if hasattr(x, "detach") else np.asarray(x)


def episode_id(chunk_id: str) -> str:
    """The id of the episode an episode chunk of a learner's batch belongs to: RLlib's learner pipeline
    (`AddOneTsToEpisodesAndTruncate`) appends `_<index in the batch>` to each chunk's id, which is otherwise the
    episode's (a hex uuid, the same for all its chunks).

    >>> episode_id("0f3a9c_12")
    '0f3a9c'
    """
    return chunk_id.rsplit("_", 1)[0]


def discounted_returns(
    rewards: np.ndarray,
    lengths: list[int],
    gamma: float,
    starts: list[float] | None = None,
    real: np.ndarray | None = None,
) -> np.ndarray:
    """The discounted return accumulated forward within each episode chunk: `rewards` holds the chunks one after
    another, `lengths` their lengths, `starts` the return each chunk's episode had before it (0 by default), and
    `real` which rows are steps (a row that is not, RLlib's bootstrap step, repeats the return before it).

    >>> discounted_returns(np.array([1.0, 1.0, 1.0, 2.0]), [3, 1], 0.5).tolist()
    [1.0, 1.5, 1.75, 2.0]
    >>> real = np.array([True, True, False, True])  # the third row is a bootstrap step
    >>> discounted_returns(np.array([1.0, 1.0, 0.0, 2.0]), [3, 1], 0.5, [2.0, 0.0], real).tolist()
    [2.0, 2.0, 2.0, 2.0]
    """
    out, start = np.empty_like(rewards, dtype=np.float64), 0
    for k, n in enumerate(lengths):
        acc = 0.0 if starts is None else float(starts[k])
        for t in range(start, start + n):
            if real is None or real[t]:
                acc = acc * gamma + rewards[t]
            out[t] = acc
        start += n
    return out


class ReturnScaledPPOLearner(PPOTorchLearner):
    """RLlib's PPO learner with :class:`ReturnScaling` before GAE, at the config's `gamma`:
    `PPOConfig().learners(learner_class=ReturnScaledPPOLearner)`. Its Adam takes `adam_eps` from the config's
    `learner_config_dict` (`--adam-eps`; torch's 1e-8, RLlib's own, where it is not given; the recipe's is 1e-5)."""

    def build(self) -> None:
        super().build()
        if self._learner_connector is not None:
            self._learner_connector.insert_before(GeneralAdvantageEstimation, ReturnScaling(gamma=self.config.gamma))

    def configure_optimizers_for_module(self, module_id: Any, config: Any = None) -> None:
        config = config or self.config
        eps = config.learner_config_dict.get("adam_eps")
        if eps is None:
            return super().configure_optimizers_for_module(module_id, config)
        import torch

        params = self.get_parameters(self._module[module_id])
        optimizer = torch.optim.Adam(params, eps=float(eps))
        self.register_optimizer(module_id=module_id, optimizer=optimizer, params=params, lr_or_lr_schedule=config.lr)
