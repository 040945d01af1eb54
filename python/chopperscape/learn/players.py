"""What plays in an evaluation: a model file (a recipe `model.pt`, a Stable-Baselines3 `.zip`) or a built-in
policy's name, loaded as an `act(obs_batch, envs) -> actions` function with the env options it plays under.

Loading never runs code from a file: a recipe model is read with `torch.load(weights_only=True)` (tensors and plain
data), and the pickled parts of an SB3 `.zip` are replaced by what the env gives, unless `trust_pickle`.
"""

from __future__ import annotations

import importlib.util
import pickle
from pathlib import Path
from typing import Any

import numpy as np

from .._checks import regular_file
from ..policies import NAMES, VectorPolicy
from ..policyfile import observation_shape, observation_space
from ..vector import VectorEnv
from .recipe import MAX_MODEL_BYTES


class BuiltinPlayer:
    """A built-in policy over each chunk of environments: policy `i` seeded as environment `i` (`S + i`)."""

    def __init__(self, name: str):
        self.name = name
        self.policy: VectorPolicy | None = None

    def start_chunk(self, n: int, seed: int) -> None:
        self.policy = VectorPolicy(self.name, n, seed=seed)

    def __call__(self, obs: np.ndarray, envs: VectorEnv) -> np.ndarray:
        assert self.policy is not None
        return self.policy.act(envs)


def load_policy(
    model: str | Path, stochastic: bool, seed: int, env_options: dict[str, Any], trust_pickle: bool = False
):
    """`(act, env_options)` for a model file (a recipe `model.pt`, a Stable-Baselines3 `.zip`) or a built-in
    policy's name.

    A bare built-in name (`"random"`, a `str`) is always that policy; a file of that name is read as `./random` (or a
    `Path`). Loading never runs code from the file (see `load_recipe`, `load_sb3`) unless `trust_pickle`."""
    if isinstance(model, str) and model in NAMES:
        return BuiltinPlayer(model), {"obs_type": "features", **env_options}
    path = Path(model)
    if not path.exists() and not path.is_symlink():
        raise ValueError(
            f"model file {str(path)!r} does not exist (give a model.pt from chopperscape.learn.train, an SB3 .zip, "
            f"or a built-in policy: {', '.join(NAMES)})"
        )
    regular_file(path, f"model file {str(path)!r}", MAX_MODEL_BYTES)
    needs = ("torch", "stable_baselines3") if path.suffix == ".zip" else ("torch",)
    missing = [m for m in needs if importlib.util.find_spec(m) is None]
    if missing:
        raise ValueError(
            f"reading model file {str(path)!r} needs {' and '.join(missing)}, which is not installed: "
            "pip install 'chopperscape[train]'"
        )
    if path.suffix == ".zip":
        return load_sb3(path, stochastic, env_options, trust_pickle)
    return load_recipe(path, stochastic, seed, env_options)


def load_recipe(path: Path, stochastic: bool, seed: int, env_options: dict[str, Any]):
    """`(act, env_options)` for a `chopperscape.learn.train` model. Read with `torch.load(weights_only=True)`: tensors
    and plain data only, so a crafted file cannot run code; its fields are then checked one by one."""
    import torch

    # One thread: a small MLP gains nothing from more, and OpenMP spinning under load can slow it by 100x.
    torch.set_num_threads(1)
    what = f"model file {str(path)!r}"
    from .modelfile import load

    agent, model_shape, norm, recipe = load(path, what)
    options = {"obs_type": recipe["obs_type"], **recipe["env_options"], **env_options}
    shape = observation_shape(options)
    if shape != model_shape:
        raise ValueError(
            f"{what} takes observations of shape {model_shape}, but these env options give observations of shape "
            f"{shape} ({_describe(options)}): evaluate it with the options it was trained with"
        )
    gen = torch.Generator().manual_seed(seed)

    def act(obs: np.ndarray, envs: VectorEnv) -> np.ndarray:
        with torch.no_grad():
            logits = agent.actor(torch.from_numpy(norm(obs)))
            if stochastic:
                return torch.multinomial(logits.softmax(-1), 1, generator=gen).squeeze(-1).numpy()
            return logits.argmax(-1).numpy()

    return act, options


def _describe(options: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v!r}" for k, v in options.items()) or "the defaults"


def load_sb3(
    path: Path, stochastic: bool, env_options: dict[str, Any], trust_pickle: bool = False, algorithm: str | None = None
):
    """`(act, env_options)` for a Stable-Baselines3 PPO or DQN `.zip` (the algorithm read from its settings), with
    the observation normalisation saved beside it.

    SB3 stores the model's settings as JSON, but some of them (the spaces, the policy class, schedules) as
    cloudpickle, which runs code when loaded; its weights are read with `weights_only=True`. Unless
    `trust_pickle`, no pickle is loaded: every pickled setting is replaced by what this env and SB3's own
    classes give (named by the readable copy SB3 stores beside it), and a setting that cannot be is refused.
    Normalisation: `vecnormalize.json` (`chopperscape.integrations.sb3_files.save_normalization`) is read as data; SB3's
    `vecnormalize.pkl` is a pickle, read only with `trust_pickle`. `algorithm` is the file's
    (`integrations.sb3_files.algorithm`) where the caller has read it already."""
    import stable_baselines3

    from ..integrations import sb3, sb3_files

    what = f"model file {str(path)!r}"
    # As the adapter gives them (`ChopperScapeVecEnv(keep_dim=True)`): grayscale with a channel axis.
    env_options = {"keep_dim": True, **env_options}
    # As SB3's policy holds them: channel-last frames (a frame stack) are transposed to channels first.
    shape = tuple(sb3.policy_space(observation_space(env_options)).shape or ())
    algorithm = algorithm or sb3_files.algorithm(path)
    if stochastic and algorithm == "DQN":
        raise ValueError(f"{what} is a DQN: its policy is greedy (argmax of Q), it cannot sample (drop --stochastic)")
    cls = getattr(stable_baselines3, algorithm)
    if trust_pickle:
        try:
            model = cls.load(path, device="cpu")
        except pickle.UnpicklingError as e:  # its weights (`policy.pth`) are read with weights_only=True anyway
            raise ValueError(f"{what}: its weights are not tensors and plain data ({str(e).splitlines()[0]})") from None
    else:
        custom = sb3_files.safe_load_objects(path, env_options)
        try:
            model = cls.load(path, device="cpu", custom_objects=custom)
        except (RuntimeError, KeyError, TypeError, AttributeError, pickle.UnpicklingError) as e:
            raise ValueError(
                f"{what} could not be read without unpickling ({str(e).splitlines()[0]}); pass "
                "--trust-pickle if you trust who made it"
            ) from None
    model_shape = tuple(model.observation_space.shape or ())
    if model_shape != shape:
        raise ValueError(
            f"{what} takes observations of shape {model_shape}, but these env options give {shape} "
            f"({_describe(env_options)}): give the options it was trained with (--option ...)"
        )
    norm = sb3_files.load_normalization(path.parent, trust_pickle)

    def act(obs: np.ndarray, envs: VectorEnv) -> np.ndarray:
        return model.predict(obs if norm is None else norm(obs), deterministic=not stochastic)[0]

    return act, env_options
