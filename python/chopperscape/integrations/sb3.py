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

Loading SB3 models without running code from them (``safe_load_objects``) and observation statistics as data
(``save_normalization`` / ``load_normalization``, in place of ``VecNormalize``'s pickle) serve
``python -m chopperscape.learn.evaluate``.

Pixel observations: SB3's ``CnnPolicy`` wants a channel axis; ``obs_type="grayscale"`` with ``keep_dim=True`` (the
default here) gives ``(H, W, 1)`` (``(H, W, k)`` with ``frame_stack=k``), which SB3 transposes to channels-first
itself.
"""

from __future__ import annotations

import json
import operator
import os
import pickle
import re
import time
import zipfile
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any, Callable

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode

try:
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv
except ImportError as err:  # pragma: no cover - exercised only without SB3
    raise ImportError("chopperscape.integrations.sb3 needs Stable-Baselines3: pip install stable-baselines3") from err

from .. import _atomic
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


# --- reading SB3 files without unpickling -------------------------------------------------------------------

#: The format of `save_normalization`'s file.
NORMALIZATION_FORMAT = "chopperscape-vecnormalize/1"
#: The SB3 algorithms whose models are read, by the module of their policy classes: the algorithm's class name and
#: the policy classes a model of it may name (PPO's live in `stable_baselines3.common.policies`, DQN's in its own).
ALGORITHMS: dict[str, tuple[str, tuple[str, ...]]] = {
    "stable_baselines3.common.policies": (
        "PPO",
        ("ActorCriticPolicy", "ActorCriticCnnPolicy", "MultiInputActorCriticPolicy"),
    ),
    "stable_baselines3.dqn.policies": ("DQN", ("DQNPolicy", "CnnPolicy", "MultiInputPolicy")),
}
#: Modules whose classes a model's `policy_kwargs` may name (activations, optimisers, SB3's feature extractors).
_KWARG_MODULES = ("torch.nn.modules.activation", "torch.optim.", "stable_baselines3.common.torch_layers")


#: Pickled settings that only training reads (schedules, DQN's training frequency), and the constants that replace them.
_TRAINING_ONLY: dict[str, Any] = {
    "learning_rate": 0.0,
    "lr_schedule": lambda _: 0.0,
    "clip_range": 0.2,
    "clip_range_vf": None,
    "exploration_schedule": lambda _: 0.0,
    "train_freq": (1, "step"),
}


def _untrusted(path: Path, what: str) -> ValueError:
    return ValueError(
        f"{path}: {what}; reading it would mean unpickling, which runs code from the file: pass --trust-pickle "
        "(trust_pickle=True) only if you trust who made it"
    )


def _named_class(text: Any, modules: Sequence[str]) -> type | None:
    """The class SB3's readable copy names (`"<class 'torch.nn.modules.activation.ReLU'>"`) if it lives in one of
    `modules`, imported by name (no unpickling); else None."""
    import importlib

    m = re.fullmatch(r"<class '([\w.]+)\.(\w+)'>", text) if isinstance(text, str) else None
    if m is None or not any(m.group(1) == mod or m.group(1).startswith(mod) for mod in modules):
        return None
    cls = getattr(importlib.import_module(m.group(1)), m.group(2), None)
    return cls if isinstance(cls, type) else None


def policy_space(space: gym.Space) -> gym.Space:
    """The observation space an SB3 policy trained on an env of `space` holds: SB3 wraps a channel-last image
    space (grayscale frames with `frame_stack`, RGB) in `VecTransposeImage`, so its policy takes channels first;
    any other space unchanged. Its `predict` transposes the env's observations itself."""
    from stable_baselines3.common.preprocessing import is_image_space, is_image_space_channels_first
    from stable_baselines3.common.vec_env import VecTransposeImage

    if isinstance(space, gym.spaces.Box) and is_image_space(space) and not is_image_space_channels_first(space):
        return VecTransposeImage.transpose_space(space)
    return space


#: The largest `data` member (the settings, JSON) of an SB3 model file read: 16 MiB (SB3 writes tens of KiB).
MAX_SB3_DATA_BYTES = 16 << 20
#: The most an SB3 model file's members may hold together, uncompressed: 1 GiB (a policy's weights and optimiser
#: state take a few MiB to tens of MiB). Checked on the archive's directory, before any member is read.
MAX_SB3_BYTES = 1 << 30
#: The largest `vecnormalize.json` read: 16 MiB (a frame stack's statistics take about 1 MiB).
MAX_NORMALIZATION_BYTES = 16 << 20


def _check_members(z: zipfile.ZipFile, path: Path) -> None:
    """`ValueError` for an archive whose members would inflate past the limits (`MAX_SB3_DATA_BYTES` for `data`,
    `MAX_SB3_BYTES` together), said from its directory before anything is inflated. A member cannot inflate past
    the size its directory declares: `zipfile` stops there (and refuses the member's checksum)."""
    infos = z.infolist()
    total = sum(i.file_size for i in infos)
    data = next((i.file_size for i in infos if i.filename == "data"), 0)
    if data > MAX_SB3_DATA_BYTES or total > MAX_SB3_BYTES:
        raise ValueError(
            f"{path}: its members inflate to {total:,} bytes ({data:,} of settings), more than the "
            f"{MAX_SB3_BYTES:,} ({MAX_SB3_DATA_BYTES:,}) a Stable-Baselines3 model file may hold"
        )


def _model_data(path: Path) -> dict[str, Any]:
    """The readable settings (`data`, JSON) of an SB3 model file; `ValueError` for a file that is not one, or whose
    members inflate past the limits (`_check_members`)."""
    not_one = f"{path} is not a Stable-Baselines3 model (a zip with its `data` settings)"
    try:
        z = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as e:
        raise ValueError(f"{not_one}: {e}") from None
    with z:
        _check_members(z, path)
        try:
            data = json.loads(z.read("data"))
        except RecursionError:
            raise ValueError(f"{path} is not a Stable-Baselines3 model: its `data` is nested too deeply") from None
        except (zipfile.BadZipFile, KeyError, ValueError, OSError, EOFError) as e:
            raise ValueError(f"{not_one}: {e}") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path} is not a Stable-Baselines3 model: its `data` is not a JSON object")
    return data


def _policy_class(path: Path, data: dict[str, Any]) -> tuple[str, str, str]:
    """`(algorithm, module, class)` of the policy class an SB3 model names in its readable copy (no unpickling);
    `ValueError` if it is not one of `ALGORITHMS`'."""
    item = data.get("policy_class")
    item = item if isinstance(item, dict) else {}
    m = re.match(r"<function (\w+)\.__init__ at ", str(item.get("__init__", "")))
    module = item.get("__module__")
    if module not in ALGORITHMS or m is None or m.group(1) not in ALGORITHMS[module][1]:
        raise _untrusted(path, "its policy class is not one of Stable-Baselines3's PPO or DQN policies")
    return ALGORITHMS[module][0], module, m.group(1)


def algorithm(path: str | os.PathLike) -> str:
    """The SB3 algorithm (`"PPO"`, `"DQN"`) a model file was saved by, read from its settings without unpickling;
    `ValueError` for a file that is not an SB3 model of one of `ALGORITHMS`."""
    path = Path(path)
    return _policy_class(path, _model_data(path))[0]


def safe_load_objects(path: str | os.PathLike, env_options: dict[str, Any]) -> dict[str, Any]:
    """`custom_objects` for `PPO.load` or `DQN.load(path, custom_objects=...)` that replace every pickled setting of
    an SB3 model, so that loading it runs no code from the file: the spaces are this env's (`env_options`; the stored
    shape is checked against them), the policy class is SB3's own one the file names, schedules are constants
    (they matter only for training), `policy_kwargs` are rebuilt from their readable copy (classes only from
    torch's activations and optimisers and SB3's feature extractors), and pickled training state (buffers, last
    observations) is dropped. `ValueError` for a file that is not an SB3 model or names anything else."""
    import importlib

    path = Path(path)
    data = _model_data(path)
    venv = VectorEnv(1, num_threads=1, max_episode_steps=None, **env_options)
    obs_space, act_space = policy_space(venv.single_observation_space), venv.single_action_space
    venv.close()
    custom: dict[str, Any] = {}
    for key, item in data.items():
        if not (isinstance(item, dict) and ":serialized:" in item):
            continue
        if key == "observation_space":
            stored = item.get("_shape")
            if isinstance(stored, list) and tuple(stored) != tuple(obs_space.shape or ()):
                raise ValueError(
                    f"{path} takes observations of shape {tuple(stored)}, but these env options give "
                    f"{tuple(obs_space.shape or ())}: give the options it was trained with (--option ...)"
                )
            custom[key] = obs_space
        elif key == "action_space":
            custom[key] = act_space
        elif key == "policy_class":
            _, module, name = _policy_class(path, data)
            custom[key] = getattr(importlib.import_module(module), name)
        elif key in _TRAINING_ONLY:
            custom[key] = _TRAINING_ONLY[key]
        elif key == "policy_kwargs":
            kwargs = {}
            for name, value in item.items():
                if name in (":type:", ":serialized:"):
                    continue
                if isinstance(value, str) and value.startswith("<"):
                    cls = _named_class(value, _KWARG_MODULES)
                    if cls is None:
                        raise _untrusted(path, f"its policy_kwargs[{name!r}] is {value}")
                    value = cls
                kwargs[name] = value
            custom[key] = kwargs
        else:
            custom[key] = None  # training state (buffers, last observations, episode statistics)
    if "buffer_size" in data:  # an off-policy model (DQN): playing needs no replay buffer, so none is allocated
        custom["buffer_size"] = 1
    return custom


def save_normalization(vec_normalize: Any, path: str | os.PathLike) -> None:
    """Writes the observation statistics of SB3's `VecNormalize` as JSON (data, not a pickle), for
    `python -m chopperscape.learn.evaluate` to read from `vecnormalize.json` beside a model."""
    rms = vec_normalize.obs_rms
    doc = {
        "format": NORMALIZATION_FORMAT,
        "norm_obs": bool(vec_normalize.norm_obs),
        "mean": np.asarray(rms.mean, np.float64).tolist(),
        "var": np.asarray(rms.var, np.float64).tolist(),
        "clip_obs": float(vec_normalize.clip_obs),
        "epsilon": float(vec_normalize.epsilon),
    }
    _atomic.write_text(path, json.dumps(doc))


def load_normalization(
    folder: str | os.PathLike, trust_pickle: bool = False
) -> Callable[[np.ndarray], np.ndarray] | None:
    """The observation normalisation saved in `folder` as SB3's `VecNormalize` applies it at evaluation:
    `vecnormalize.json` (`save_normalization`) is read as data; `vecnormalize.pkl` (`VecNormalize.save`) is a
    pickle, read only with `trust_pickle` (else `ValueError` saying how to convert it); None when there is
    neither."""
    folder = Path(folder)
    data, pkl = folder / "vecnormalize.json", folder / "vecnormalize.pkl"
    if data.is_file():
        from .._checks import regular_file

        regular_file(data, str(data), MAX_NORMALIZATION_BYTES)
        try:
            doc = json.loads(data.read_text())
            ok = isinstance(doc, dict) and doc.get("format") == NORMALIZATION_FORMAT
            mean, var = np.asarray(doc["mean"], np.float64), np.asarray(doc["var"], np.float64)
            clip, eps, on = float(doc["clip_obs"]), float(doc["epsilon"]), doc["norm_obs"]
            ok = ok and mean.shape == var.shape and mean.ndim >= 1 and isinstance(on, bool)
            ok = ok and bool(np.isfinite(mean).all() and (var >= 0).all() and clip > 0 and eps > 0)
        except RecursionError:
            raise ValueError(f"{data} is not a usable normalisation file: it is nested too deeply") from None
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise ValueError(f"{data} is not a usable normalisation file: {e}") from None
        if not ok:
            raise ValueError(f"{data} is not a usable normalisation file (format {NORMALIZATION_FORMAT})")
        if not on:
            return None
        scale = np.sqrt(var + eps)
        return lambda obs: np.clip((obs - mean) / scale, -clip, clip).astype(np.float32)
    if pkl.is_file():
        if not trust_pickle:
            raise ValueError(
                f"{pkl} is a pickle (SB3's VecNormalize.save), which runs code when loaded: pass --trust-pickle if "
                f"you trust who made it, or save its statistics as data with "
                f"chopperscape.integrations.sb3.save_normalization(vec_normalize, {str(data)!r})"
            )
        with open(pkl, "rb") as f:
            norm = pickle.load(f)
        norm.training = False
        return norm.normalize_obs
    return None
