"""`VectorEnv`: N ChopperScape environments stepped by one Rust call, as a `gymnasium.vector.VectorEnv`."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from . import _core
from ._checks import check_bool, check_reset_options, core_seed, positive_int, time_limit
from ._spaces import batched_box, channel_axis, observation_box

_CAUSES = np.array([None, *_core.CAUSE_NAMES[1:]], dtype=object)


#: Worker threads when `num_threads` is not given: one, whatever the batch size.
#:
#: Measured on the 2-vCPU machines this is developed on (python/README.md, "Threads"): a second thread wins only
#: for large batches on an idle host, and loses badly (up to 4× slower) when anything else wants the CPU, which is
#: the usual case while a learner trains beside the env. `os.sched_getaffinity` says how many CPUs this process
#: may use; pass `num_threads` up to that for N ≥ 1024 after measuring with `python/bench.py`.
DEFAULT_THREADS = 1


class VectorEnv(gym.vector.VectorEnv):
    """`num_envs` ChopperScape-v0 environments stepped together in Rust, over `num_threads` threads.

    `gymnasium.make_vec("ChopperScape-v0", num_envs=N, vectorization_mode="vector_entry_point", ...)` builds one;
    so does `chopperscape.VectorEnv(N, ...)`. It takes every option of `ChopperScapeEnv` as a keyword, and:

    | Argument | Default | Meaning |
    |----------|---------|---------|
    | `num_threads` | 1 | worker threads (results do not depend on it); more pay only for large batches on idle cores (see `DEFAULT_THREADS`) |
    | `copy` | `True` | `True`: every call returns fresh arrays. `False`: every call returns *the same* preallocated arrays, read-only (`writeable=False`), overwritten by the next `step`/`reset` (copy what you keep: pixel observations are drawn incrementally onto the previous frame). A bool |
    | `autoreset_mode` | `AutoresetMode.NEXT_STEP` | or `AutoresetMode.SAME_STEP` (final observations in `info["final_obs"]`) |
    | `max_episode_steps` | 10000 | truncation, exactly as Gymnasium's `TimeLimit`; `None` never truncates |
    | `keep_dim` | `False` | `"grayscale"` without stacking as `(N, H, W, 1)`, with a channel axis (a view, no copy) |
    | `render_mode` | `None` | `"rgb_array"`: `render()` returns a tuple of 600 × 800 × 3 frames |

    Environment `i` of a batch reset with `seed=s` follows the trajectory of a single `ChopperScape-v0` seeded
    `s + i`, across autoresets (which continue each environment's own generator, as `reset()` does).

    `step(actions)` takes `num_envs` integer actions in `0..=4`; a wrong shape, dtype or value raises
    `ValueError` and moves no environment. Infos follow Gymnasium's vector convention: `info["fuel"]`,
    `info["lives"]` (int64 arrays) with masks `info["_fuel"]`, `info["_lives"]` (one shared read-only
    all-true array), and `info["cause"]` (an object
    array of `"bird"`, `"fuel"` or `None`) with `info["_cause"]` when some episode terminated.
    """  # noqa: E501 - the Markdown table above cannot wrap

    metadata = {  # noqa: RUF012 - Gymnasium declares `metadata` a plain attribute
        "autoreset_mode": AutoresetMode.NEXT_STEP,
        "render_modes": ["rgb_array"],
        "render_fps": _core.RENDER_FPS,
    }

    def __init__(
        self,
        num_envs: int,
        num_threads: int | None = None,
        copy: bool = True,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        max_episode_steps: int | None = 10_000,
        render_mode: str | None = None,
        keep_dim: bool = False,
        **options: Any,
    ):
        num_envs = positive_int("num_envs", num_envs)
        if num_threads is None:
            num_threads = DEFAULT_THREADS
        num_threads = positive_int("num_threads", num_threads)
        mode: AutoresetMode | None
        try:
            mode = AutoresetMode(autoreset_mode)
        except ValueError:
            mode = None
        if mode not in (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP):
            raise ValueError(
                "invalid value for option `autoreset_mode`: allowed AutoresetMode.NEXT_STEP or AutoresetMode.SAME_STEP"
            )
        copy = check_bool("copy", copy)
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"invalid value {render_mode!r} for option `render_mode`: allowed None, 'rgb_array'")
        max_episode_steps = time_limit(max_episode_steps)
        self._core_args = (
            int(num_envs),
            int(num_threads),
            {**options, "max_episode_steps": None},
            mode == AutoresetMode.SAME_STEP,
            bool(copy),
            None if max_episode_steps is None else int(max_episode_steps),
        )
        self._core = _core.VectorEnv(*self._core_args)
        self._options = dict(options)
        self.num_envs = int(num_envs)
        self.num_threads = self._core.num_threads
        self.copy = bool(copy)
        self.render_mode = render_mode
        self.autoreset_mode = mode
        self.metadata = {**type(self).metadata, "autoreset_mode": mode}
        self.max_episode_steps = max_episode_steps
        self._keep_dim = channel_axis(keep_dim, self._core)
        self.single_observation_space = observation_box(self._core, self._keep_dim)
        self.observation_space = batched_box(self.single_observation_space, self.num_envs)
        self.single_action_space = spaces.Discrete(len(_core.ACTION_MEANINGS))
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._stream_started = False
        # Every environment has fuel and lives every step: one shared all-true mask, read-only for good (its
        # memory is a bytes object, so numpy refuses to make it writable again).
        self._all = np.frombuffer(b"\x01" * self.num_envs, dtype=np.bool_)

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Resets every environment. `seed=s` seeds environment `i` with `s + i`; a list gives each its own seed
        (`None` continues that one's stream); no seed continues every stream (the first time, a seed is drawn
        from `np_random`, itself seeded from OS entropy)."""
        check_reset_options(options)
        if isinstance(seed, (list, tuple)):
            if len(seed) != self.num_envs:
                raise ValueError(
                    f"If seeds are passed as a list the length must match num_envs={self.num_envs} but got "
                    f"length={len(seed)}."
                )
            seeds = [None if s is None else core_seed(s, f"seed at index {i}") for i, s in enumerate(seed)]
            out = self._core.reset_seeds(seeds)
        else:
            if seed is not None:
                core = core_seed(seed)
                super().reset(seed=int(seed))
            elif not self._stream_started:
                core = int(self.np_random.integers(0, 2**63))
            else:
                core = None
            out = self._core.reset(core)
        self._stream_started = True
        obs, _, _, _, fuel, lives, _, _ = out
        return self._shaped(obs), self._infos(fuel, lives)

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Steps every environment; see the class docstring for autoreset and infos."""
        if not (
            type(actions) is np.ndarray
            and actions.dtype == np.int64
            and actions.shape == (self.num_envs,)
            and actions.flags.c_contiguous
        ):
            actions = self._checked_actions(actions)
        obs, rewards, terminated, truncated, fuel, lives, cause, final_obs = self._core.step(actions)
        if final_obs is None:
            infos = self._infos(fuel, lives, cause)
        else:
            infos = self._same_step_infos(final_obs, terminated | truncated, fuel, lives, cause)
        return self._shaped(obs), rewards, terminated, truncated, infos

    def _shaped(self, obs: np.ndarray) -> np.ndarray:
        """With `keep_dim`, the batch of 2-D frames as `(N, H, W, 1)`: a view, read-only if `obs` is."""
        return obs[..., None] if self._keep_dim else obs

    def _checked_actions(self, actions: Any) -> np.ndarray:
        """`actions` as a contiguous int64 array, or `ValueError` naming what is wrong (values are checked in Rust)."""
        actions = np.asarray(actions)
        if actions.shape != (self.num_envs,):
            raise ValueError(
                f"actions must have shape ({self.num_envs},) (one action per environment), got {actions.shape}"
            )
        if actions.dtype.kind not in "iu":
            raise ValueError(f"actions must be integers in 0..=4, got dtype {actions.dtype}")
        if actions.dtype != np.int64:
            if actions.dtype.kind == "u" and actions.size and actions.max() > 4:
                bad = int(np.argmax(actions > 4))
                raise ValueError(
                    f"invalid action {actions[bad]} at index {bad}: allowed actions are 0..=4 "
                    "(0 Right, 1 Left, 2 Down, 3 Up, 4 Do Nothing)"
                )
            actions = actions.astype(np.int64)
        return np.ascontiguousarray(actions)

    def _infos(self, fuel: np.ndarray, lives: np.ndarray, cause: np.ndarray | None = None) -> dict[str, Any]:
        infos: dict[str, Any] = {"fuel": fuel, "_fuel": self._all, "lives": lives, "_lives": self._all}
        if cause is not None and cause.any():
            infos["cause"] = _CAUSES[cause]
            infos["_cause"] = cause != 0
        return infos

    def _same_step_infos(
        self, final_obs: np.ndarray, ended: np.ndarray, fuel: np.ndarray, lives: np.ndarray, cause: np.ndarray
    ) -> dict[str, Any]:
        if not ended.any():
            return self._infos(fuel, lives)
        # The ended environments were reset in this step: their info is the reset info.
        infos = self._infos(np.where(ended, self._core.max_fuel, fuel), np.where(ended, self._core.lives, lives))
        objs = np.full(self.num_envs, None, dtype=object)
        for i in np.flatnonzero(ended):
            objs[i] = self._shaped(final_obs[i].copy())
        final_info: dict[str, Any] = {
            "fuel": np.where(ended, fuel, 0),
            "_fuel": ended.copy(),
            "lives": np.where(ended, lives, 0),
            "_lives": ended.copy(),
        }
        if cause.any():
            final_info["cause"] = _CAUSES[cause]
            final_info["_cause"] = cause != 0
        infos.update(
            {"final_obs": objs, "_final_obs": ended.copy(), "final_info": final_info, "_final_info": ended.copy()}
        )
        return infos

    def batch_state(self) -> tuple[bool, list[tuple[bytes, bool, int]]]:
        """Every environment's whole state (snapshot bytes, whether it awaits its reset, its step count) and
        whether the batch has been reset: what pickling and `train --resume` save."""
        return self._core.state()

    def set_batch_state(self, started: bool, envs: list[tuple[bytes, bool, int]]) -> None:
        """Puts the batch in a state :meth:`batch_state` took (each snapshot checked by the core: `ValueError`
        naming what is wrong, and nothing changes)."""
        self._core.set_state(started, envs)
        self._stream_started = bool(started) or self._stream_started

    def __getstate__(self) -> dict[str, Any]:
        """Pickles the options and every environment's state; unpickling continues exactly from there."""
        state = self.__dict__.copy()
        state["_core"] = self.batch_state()
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        core_state = state.pop("_core")
        self.__dict__.update(state)
        self._core = _core.VectorEnv(*self._core_args)
        self._core.set_state(*core_state)
        self._all = np.frombuffer(b"\x01" * self.num_envs, dtype=np.bool_)

    def render(self) -> tuple[np.ndarray, ...] | None:
        """`render_mode="rgb_array"`: one 600 × 800 × 3 frame per environment."""
        if self.render_mode is None:
            gym.logger.warn("You are calling render method without specifying any render mode.")
            return None
        return tuple(self._core.render(i) for i in range(self.num_envs))

    def get_action_meanings(self) -> list[str]:
        """The name of each action, by index."""
        return list(_core.ACTION_MEANINGS)

    def env_state(self, i: int) -> bytes:
        """Environment `i`'s whole state as bytes: `ChopperScapeEnv.restore_state` reads them."""
        return self._core.snapshot(self.env_index(i))

    def env_index(self, i: Any) -> int:
        """`i` as the index of one of the environments, or `IndexError` naming the range."""
        if isinstance(i, (bool, np.bool_)) or not isinstance(i, (int, np.integer)) or not 0 <= i < self.num_envs:
            raise IndexError(f"environment {i!r} does not exist: allowed 0..={self.num_envs - 1}")
        return int(i)
