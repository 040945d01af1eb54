"""Stable-Baselines3's files read as data: a model `.zip` loaded without unpickling (`algorithm`,
`safe_load_objects`: every pickled setting replaced by what this env and SB3's own classes give, the archive's
sizes checked before anything is inflated), and observation statistics in place of `VecNormalize`'s pickle
(`save_normalization` / `load_normalization`, `vecnormalize.json`). `python -m chopperscape.learn.evaluate` and the
bench read SB3 models through them; the adapter itself is :mod:`chopperscape.integrations.sb3`.
"""

from __future__ import annotations

import json
import os
import pickle
import re
import zipfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .. import _atomic
from ..vector import VectorEnv
from .sb3 import policy_space

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
