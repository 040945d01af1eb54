"""Stable-Baselines3 adapter: the native batch as an SB3 `VecEnv`, with SB3's own semantics.

    from stable_baselines3 import PPO
    from chopperscape.integrations.sb3 import ChopperScapeVecEnv

    env = ChopperScapeVecEnv(16, obs_type="features", seed=0)
    model = PPO("MlpPolicy", env).learn(100_000)

It behaves as ``make_vec_env("ChopperScape-v0", n_envs=N, seed=s)`` does (``DummyVecEnv`` over ``Monitor``-wrapped
envs), trajectory for trajectory, but steps every environment in one Rust call:

- ``step`` returns ``dones = terminated | truncated``; a finished environment is reset in the same step, its reset
  observation is returned, and its last observation is in ``infos[i]["terminal_observation"]`` (no phantom
  transition: SB3 never sees Gymnasium's NEXT_STEP reset step);
- ``infos[i]["TimeLimit.truncated"]`` is ``truncated and not terminated``; ``infos[i]`` also has ``fuel``,
  ``lives``, ``cause`` (on termination) and, at an episode's end, ``episode = {"r", "l", "t"}`` as SB3's ``Monitor``
  writes it, so ``PPO``'s ``ep_rew_mean`` logging works without a wrapper;
- ``seed(s)`` (what SB3 calls) seeds environment ``i`` with ``s + i`` at the next ``reset``; autoresets continue each
  environment's own generator, as ``DummyVecEnv`` resets do;
- the rest of SB3's ``VecEnv`` contract as ``DummyVecEnv`` keeps it (tested call for call): actions of shape
  ``(num_envs,)`` only, never reshaped; ``get_attr``/``env_method`` indices in range (negative ones from the end).
  Where ``DummyVecEnv`` stores a bad ``seed()`` or non-empty ``set_options()`` and fails at every later ``reset``,
  this adapter refuses the call itself and changes nothing; a failed step's actions are not reused.

Loading SB3 models without running code from them and observation statistics as data (in place of
``VecNormalize``'s pickle) are :mod:`chopperscape.integrations.sb3_files`.

Pixel observations: SB3's ``CnnPolicy`` wants a channel axis; ``obs_type="grayscale"`` with ``keep_dim=True`` (the
default here) gives ``(H, W, 1)`` (``(H, W, k)`` with ``frame_stack=k``), which SB3 transposes to channels-first
itself.
"""

from __future__ import annotations

import operator
import time
from collections.abc import Iterable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode

try:
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv
except ImportError as err:  # pragma: no cover - exercised only without SB3
    raise ImportError("chopperscape.integrations.sb3 needs Stable-Baselines3: pip install stable-baselines3") from err

from .._checks import check_reset_options, core_seed
from ..vector import VectorEnv


def ppo_settings(recipe: Any) -> dict[str, Any]:
    """SB3 `PPO`'s keyword arguments for a recipe (:class:`chopperscape.learn.recipe.Recipe`): its rollout, batch,
    epochs, γ, GAE λ, clip, coefficients, gradient clip and network ([hidden, hidden] for the actor and the critic,
    SB3's MlpPolicy tanh), all but the learning rate, whose schedule is the caller's."""
    r = recipe
    return {
        "n_steps": r.num_steps,
        "batch_size": r.num_envs * r.num_steps // r.num_minibatches,
        "n_epochs": r.update_epochs,
        "gamma": r.gamma,
        "gae_lambda": r.gae_lambda,
        "clip_range": r.clip_coef,
        "ent_coef": r.ent_coef,
        "vf_coef": r.vf_coef,
        "max_grad_norm": r.max_grad_norm,
        "policy_kwargs": {"net_arch": [r.hidden, r.hidden]},
    }


class ChopperScapeVecEnv(VecEnv):
    """`num_envs` ChopperScape environments as one SB3 `VecEnv` (see the module docs).

    Every option of ``ChopperScapeEnv`` is a keyword (``obs_type``, ``lives``, ``frame_skip``…), plus
    ``num_threads`` and ``max_episode_steps`` (default 10,000, as the registered env) of ``VectorEnv``, ``seed``
    (the seed of the first reset; ``None`` draws one) and ``keep_dim`` (grayscale with a channel axis, default
    ``True``).
    """

    def __init__(
        self,
        num_envs: int,
        seed: int | None = None,
        keep_dim: bool = True,
        render_mode: str | None = None,
        **options: Any,
    ):
        self.venv = VectorEnv(
            num_envs,
            autoreset_mode=AutoresetMode.SAME_STEP,
            copy=True,
            render_mode=render_mode,
            keep_dim=keep_dim,
            **options,
        )
        self.render_mode = render_mode
        super().__init__(self.venv.num_envs, self.venv.single_observation_space, self.venv.single_action_space)
        self.metadata = self.venv.metadata
        self._actions: np.ndarray | None = None
        self._ep_return = np.zeros(self.num_envs, np.float64)
        self._ep_len = np.zeros(self.num_envs, np.int64)
        self._t0 = time.perf_counter()
        #: The seeds of the last reset, one per environment (`None` for one reset without a seed; `None` before
        #: any reset): an SB3 run's training seeds, since autoresets continue each environment's own generator.
        self.reset_seeds: list[int | None] | None = None
        if seed is not None:
            self.seed(seed)

    def seed(self, seed: int | None = None) -> Sequence[int | None]:
        """Seeds environment `i` with `seed + i` at the next `reset` (SB3's `VecEnv.seed`; `None` draws a seed).
        A seed the envs cannot take (negative, not an integer) is refused here, changing nothing, instead of
        breaking every later `reset`."""
        if seed is not None:
            seed = core_seed(seed)
        return super().seed(seed)

    def set_options(self, options: list[dict] | dict | None = None) -> None:
        """SB3's `VecEnv.set_options`: ChopperScape's reset takes no options, so only empty ones are accepted;
        others are refused here, changing nothing (a list must hold one dict per environment)."""
        given = [options] if options is None or isinstance(options, dict) else list(options)
        if not isinstance(options, (dict, type(None))) and len(given) != self.num_envs:
            raise ValueError(f"set_options takes one dict per environment ({self.num_envs}), got {len(given)}")
        for o in given:
            check_reset_options(o)
        super().set_options(options)

    def reset(self) -> np.ndarray:
        seeds = self._seeds
        self.reset_seeds = [None if s is None else int(s) for s in seeds]
        if all(s is None for s in seeds):
            obs, info = self.venv.reset()
        else:
            obs, info = self.venv.reset(seed=list(seeds))
        self._reset_seeds()
        self._reset_options()
        self._ep_return[:] = 0
        self._ep_len[:] = 0
        self.reset_infos = [
            {"fuel": int(info["fuel"][i]), "lives": int(info["lives"][i])} for i in range(self.num_envs)
        ]
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        """Takes one action per environment: shape `(num_envs,)`, integers (as `DummyVecEnv`, which hands
        `actions[i]` to env `i`); anything else is refused here, never reshaped."""
        self._actions = None
        self._actions = self.venv._checked_actions(actions).copy()

    def step_wait(self):
        # The actions are used once: after a failed step, step_wait() without a new step_async() is refused.
        actions, self._actions = self._actions, None
        if actions is None:
            raise RuntimeError("step_wait() called without step_async()")
        obs, rewards, terminated, truncated, info = self.venv.step(actions)
        dones = terminated | truncated
        self._ep_return += rewards
        self._ep_len += 1
        final_info = info.get("final_info", {})
        infos: list[dict[str, Any]] = []
        for i in range(self.num_envs):
            if dones[i]:
                d: dict[str, Any] = {
                    "fuel": int(final_info["fuel"][i]),
                    "lives": int(final_info["lives"][i]),
                    "TimeLimit.truncated": bool(truncated[i] and not terminated[i]),
                    "terminal_observation": info["final_obs"][i],
                    "episode": {
                        "r": float(self._ep_return[i]),
                        "l": int(self._ep_len[i]),
                        "t": round(time.perf_counter() - self._t0, 6),
                    },
                }
                if "_cause" in final_info and final_info["_cause"][i]:
                    d["cause"] = str(final_info["cause"][i])
                self._ep_return[i], self._ep_len[i] = 0.0, 0
            else:
                d = {"fuel": int(info["fuel"][i]), "lives": int(info["lives"][i]), "TimeLimit.truncated": False}
            infos.append(d)
        return obs, rewards.astype(np.float32), dones, infos

    def close(self) -> None:
        self.venv.close()

    def get_images(self) -> Sequence[np.ndarray | None]:
        if self.render_mode != "rgb_array":
            return [None] * self.num_envs
        return list(self.venv.render() or ())

    # The attribute API of VecEnv. There is one native env, not N Python objects: attributes are the batch's.
    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        return [getattr(self.venv, attr_name) for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        raise AttributeError(
            f"cannot set `{attr_name}`: the environments of a ChopperScapeVecEnv are one native batch; "
            "make a new ChopperScapeVecEnv with other options instead"
        )

    def env_method(self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any) -> list[Any]:
        if method_name == "get_action_meanings":
            return [self.venv.get_action_meanings() for _ in self._get_indices(indices)]
        if method_name == "env_state":
            return [self.venv.env_state(i) for i in self._get_indices(indices)]
        raise AttributeError(
            f"env_method({method_name!r}) is not supported: allowed 'get_action_meanings', 'env_state'"
        )

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper], indices: Any = None) -> list[bool]:
        # Episode statistics are written as Monitor writes them, so SB3's evaluate_policy may treat it as wrapped.
        from stable_baselines3.common.monitor import Monitor

        return [wrapper_class is Monitor for _ in self._get_indices(indices)]

    def _get_indices(self, indices: Any) -> Iterable[int]:
        """Environment indices as `DummyVecEnv` takes them (`None`: all; an int; an iterable of ints; negative
        ones count from the end), or `IndexError` / `TypeError` as a list of the environments would raise."""
        if indices is None:
            return range(self.num_envs)
        if isinstance(indices, int):
            indices = [indices]
        out = []
        for i in indices:
            i = operator.index(i)
            if not -self.num_envs <= i < self.num_envs:
                raise IndexError(f"environment index {i} out of range: allowed {-self.num_envs}..={self.num_envs - 1}")
            out.append(i % self.num_envs)
        return out


def policy_space(space: gym.Space) -> gym.Space:
    """The observation space an SB3 policy trained on an env of `space` holds: SB3 wraps a channel-last image
    space (grayscale frames with `frame_stack`, RGB) in `VecTransposeImage`, so its policy takes channels first;
    any other space unchanged. Its `predict` transposes the env's observations itself."""
    from stable_baselines3.common.preprocessing import is_image_space, is_image_space_channels_first
    from stable_baselines3.common.vec_env import VecTransposeImage

    if isinstance(space, gym.spaces.Box) and is_image_space(space) and not is_image_space_channels_first(space):
        return VecTransposeImage.transpose_space(space)
    return space
