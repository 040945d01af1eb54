"""The recipe's model file, format ``chopperscape-ppo/1``: what :mod:`.train` saves (:func:`save`) and
:mod:`.evaluate`, :mod:`.export` and the teacher read (:func:`load`). The policy's networks, its frozen observation
statistics and the recipe it was trained with.

The file holds tensors and plain data only, so it is read with ``torch.load(weights_only=True)``: a crafted file
cannot run code (:func:`read_checkpoint`). :func:`load` reads one and checks it field by field, the network's
claimed sizes against the weights before anything is built.
"""

from __future__ import annotations

import math
import pickle
import re
import warnings
import zipfile
from dataclasses import asdict
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

try:
    import torch
except ImportError as err:  # pragma: no cover - exercised only without torch
    raise ImportError(
        "chopperscape.learn needs PyTorch: pip install 'chopperscape[train]' (the CPU build of torch is enough)"
    ) from err

from .. import FEATURES_VERSION, NUM_ACTIONS, PIXELS_VERSION, _atomic, _core, _signals
from .._checks import regular_file
from ..options import ENV_OPTIONS
from .networks import ActorCritic, build_agent
from .normalize import ObsNormalizer, RunningMeanStd
from .recipe import MAX_MODEL_BYTES, RESERVED_OPTIONS, Recipe, network_of

#: The checkpoint format this module writes and reads.
FORMAT = "chopperscape-ppo/1"


def agent_from_checkpoint(payload: Any, what: str = "the checkpoint") -> ActorCritic:
    """Rebuilds the agent a checkpoint (see :func:`save`) holds, with its weights, in eval mode. `ValueError`
    naming the first field that is missing or of the wrong kind, or a layout version other than this package's."""

    def bad(field: str, expected: str) -> ValueError:
        return ValueError(f"{what} is not a usable chopperscape.learn.train model: `{field}` {expected}")

    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise ValueError(f"{what} is not a chopperscape.learn.train model (format {FORMAT})")
    recipe = payload.get("recipe")
    if not isinstance(recipe, dict) or not isinstance(recipe.get("env_options", {}), dict):
        raise bad("recipe", "must be the recipe's settings (a dict with env_options)")
    check_env_options(recipe.get("env_options", {}), what)
    obs_dim, hidden = payload.get("obs_dim"), recipe.get("hidden")
    for field, value in (("obs_dim", obs_dim), ("recipe.hidden", hidden), ("num_actions", payload.get("num_actions"))):
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 1 << 24:
            raise bad(field, "must be a positive integer")
    if payload["num_actions"] != NUM_ACTIONS or not isinstance(recipe.get("obs_type"), str):
        raise bad("num_actions/recipe.obs_type", f"must be {NUM_ACTIONS} actions and an observation type")
    shape = payload.get("obs_shape", [obs_dim])
    if (
        not isinstance(shape, list)
        or not 1 <= len(shape) <= 3
        or not all(isinstance(d, int) and not isinstance(d, bool) and 1 <= d <= 4096 for d in shape)
        or math.prod(shape) != obs_dim
    ):
        raise bad("obs_shape", f"must be 1 to 3 sizes in 1..=4096 whose product is obs_dim ({obs_dim})")
    pixels = recipe["obs_type"] != "features"
    learned = payload.get("pixels_version" if pixels else "features_version", 1 if pixels else 2)
    current = PIXELS_VERSION if pixels else FEATURES_VERSION
    # An older pixel layout is still drawn, under the options `_core.PIXEL_LAYOUTS` names (`learned_options`).
    if learned != current and not (pixels and learned in _core.PIXEL_LAYOUTS):
        kind = "pixel" if pixels else "features"
        raise ValueError(
            f"{what}: the model learned {kind} layout v{learned}, and this chopperscape draws v{current}: retrain "
            "it, or use the chopperscape version it was trained with"
        )
    network = network_of(recipe)
    if not isinstance(network, str):
        raise bad("recipe.network", "must be a network's name")
    # 0.1.0's models have no `invert_frames`: they read plain frames.
    invert = recipe.get("invert_frames", False) is True
    for part in ("actor", "critic"):
        state = payload.get(part)
        if not isinstance(state, dict) or not all(isinstance(v, torch.Tensor) for v in state.values()):
            raise bad(part, "must be a dict of tensors")
    # The network the recipe claims, built on the meta device (shapes, no memory): its sizes must be those of the
    # weights in the file before the real one is built, so a small file cannot claim a network of gigabytes.
    try:
        with torch.device("meta"):
            shaped = build_agent(network, tuple(shape), NUM_ACTIONS, int(hidden or 0), invert)
    except ValueError as e:
        raise bad("recipe.network", str(e)) from None
    for part in ("actor", "critic"):
        state = payload[part]
        want = {k: tuple(v.shape) for k, v in getattr(shaped, part).state_dict().items()}
        have = {k: tuple(v.shape) for k, v in state.items()}
        if want != have:
            diff = sorted(set(want) ^ set(have)) or [k for k in want if want[k] != have[k]]
            k = diff[0]
            raise bad(
                part,
                f"does not fit the {network} network (hidden {hidden}) on observations of shape {tuple(shape)}: "
                f"`{k}` is {list(have[k]) if k in have else 'missing'} where the network has "
                f"{list(want[k]) if k in want else 'no such weight'}",
            )
    agent = build_agent(network, tuple(shape), NUM_ACTIONS, int(hidden or 0), invert)
    for part in ("actor", "critic"):
        state = payload[part]
        try:
            getattr(agent, part).load_state_dict(state)
        except RuntimeError as e:
            raise bad(
                part,
                f"does not fit the {network} network on observations of shape {tuple(shape)}: {str(e).splitlines()[0]}",
            ) from None
    return agent.eval()


def check_env_options(options: dict[str, Any], what: str) -> None:
    """`ValueError` naming a model's recipe env option that no env takes, or one the recipe sets itself (`obs_type`,
    `num_threads`, `autoreset_mode`, `copy`, `render_mode`: a trainer of this package never saves them); the
    values are checked by the env that is made with them."""
    for name, value in options.items():
        if name in RESERVED_OPTIONS or name not in ENV_OPTIONS:
            why = "no env option of that name" if name not in ENV_OPTIONS else RESERVED_OPTIONS[name]
            raise ValueError(
                f"{what} is not a usable chopperscape.learn.train model: `recipe.env_options` holds `{name}` ({why})"
            )
        plain = (str, int, float, bool, type(None))
        if not isinstance(value, plain) and not (isinstance(value, list) and all(isinstance(v, plain) for v in value)):
            raise ValueError(
                f"{what} is not a usable chopperscape.learn.train model: `recipe.env_options.{name}` is a "
                f"{type(value).__name__}, not an option value"
            )


def _plain(value: Any) -> Any:
    """`value` as plain data (dicts, lists, str, int, float, bool, None), what `weights_only` loading reads."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def save(
    path: Path, agent: ActorCritic, obs_norm: ObsNormalizer, recipe: Recipe, obs_shape: tuple[int, ...], env_steps: int
) -> None:
    """Writes the policy atomically (temp file + rename): a crash or a Ctrl-C never leaves a half-written model,
    nor the temporary file. The payload is tensors and plain data only (`torch.load(weights_only=True)`).

    The payload (format ``chopperscape-ppo/1``): ``recipe`` (the :class:`Recipe` as a dict, env options included),
    ``obs_shape`` (one env's observation), ``obs_dim`` (its size), ``num_actions``, ``obs_rms`` (the observation
    statistics, or None), ``env_steps``, and the ``actor`` and ``critic`` state dicts (a CNN's shared trunk is in
    both), and the layout versions of the observations it learned from (``features_version``, ``pixels_version``).
    Models from before the pixel recipe have no ``obs_shape``, no versions and no ``recipe["network"]`` (an MLP on
    features v2)."""
    payload = {
        "format": FORMAT,
        "recipe": _plain(asdict(recipe)),
        "obs_shape": list(obs_shape),
        "obs_dim": int(np.prod(obs_shape)),
        "num_actions": NUM_ACTIONS,
        "obs_rms": obs_norm.rms.state() if obs_norm.enabled else None,
        "env_steps": int(env_steps),
        # The observation layouts the policy learned: a later layout is a different input.
        "features_version": FEATURES_VERSION,
        "pixels_version": PIXELS_VERSION,
        # Not cloned: a CNN's trunk, in both state dicts, then shares its storage and is written once.
        "actor": {k: v.detach().cpu() for k, v in agent.actor.state_dict().items()},
        "critic": {k: v.detach().cpu() for k, v in agent.critic.state_dict().items()},
    }
    with _signals.deferred(f"the model is saved in {path}"), _atomic.replacing(path) as tmp:
        torch.save(payload, tmp)


#: Terminal escape sequences (colours, bold), which some torch versions put in their messages.
_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")


def _reason(err: BaseException) -> str:
    """The line of a `torch.load` error that says what went wrong, without terminal codes or torch's advice."""
    text = _ANSI.sub("", str(err))
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    for line in lines:  # weights_only's refusal: the offending global or opcode, not the paragraph before it
        if "GLOBAL" in line or line.startswith(("Unsupported", "Trying to load")):
            return line.rstrip(".")
    useful = [line for line in lines if not line.startswith(("Weights only load failed", "Check the documentation"))]
    return (useful[0] if useful else type(err).__name__).rstrip(".")[:300]


def read_checkpoint(path: Path, what: str) -> Any:
    """The payload of a recipe model file, read with `torch.load(weights_only=True)` (tensors and plain data only: a
    crafted file cannot run code); `ValueError` in one line naming the file and the reason when it is not a regular
    file of at most `MAX_MODEL_BYTES`, is damaged, or holds more."""
    regular_file(path, what, MAX_MODEL_BYTES)
    if not zipfile.is_zipfile(path):
        raise ValueError(
            f"{what} is not a chopperscape.learn.train model: it is not a zip archive, the form torch.save writes"
        )
    try:
        with warnings.catch_warnings():  # torch's notes on pickle protocols: the refusal below says what matters
            warnings.simplefilter("ignore")
            return torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as err:
        raise ValueError(
            f"{what} is not a chopperscape.learn.train model: it holds more than tensors and plain data "
            f"({_reason(err)}), and is refused because unpickling it could run code"
        ) from None
    except Exception as err:
        reason = _reason(err)
        if len(reason) < 20:  # `KeyError: '105'` says nothing without its type
            reason = f"{type(err).__name__}: {reason}"
        raise ValueError(f"{what} is not a chopperscape.learn.train model: it is damaged ({reason})") from None


class Model(NamedTuple):
    """A loaded model: the agent (eval mode), one env's observation shape, the frozen normaliser, the recipe."""

    agent: ActorCritic
    obs_shape: tuple[int, ...]
    norm: ObsNormalizer
    recipe: dict[str, Any]


def from_payload(payload: Any, what: str = "the checkpoint") -> Model:
    """The :class:`Model` a loaded payload holds; `ValueError` naming the first field that is missing or of the
    wrong kind (:func:`agent_from_checkpoint`'s checks, then the observation statistics')."""
    agent = agent_from_checkpoint(payload, what)
    recipe, shape = payload["recipe"], tuple(payload.get("obs_shape") or (payload["obs_dim"],))
    rms = payload.get("obs_rms")
    norm = ObsNormalizer(shape, rms is not None)
    if rms is not None:
        try:
            norm.rms = RunningMeanStd.from_state(rms)
            mean = np.asarray(norm.rms.mean, dtype=np.float64)
            var = np.asarray(norm.rms.var, dtype=np.float64)
            ok = mean.shape == shape and var.shape == shape
            ok = ok and bool(np.isfinite(mean).all() and np.isfinite(var).all() and (var >= 0).all())
            norm.rms.mean, norm.rms.var = mean, var
        except (KeyError, TypeError, ValueError, OverflowError):
            ok = False
        if not ok:
            raise ValueError(
                f"{what} is not a usable chopperscape.learn.train model: `obs_rms` must hold a mean and a "
                f"variance of shape {shape}, finite numbers (variances >= 0)"
            )
    return Model(agent, shape, norm, {**recipe, "env_options": learned_options(payload)})


def learned_options(payload: dict[str, Any]) -> dict[str, Any]:
    """The env options that show a checked payload's policy what it learned from: its recipe's, over the options
    that draw the pixel layout it learned where that is an older one (a model of pixel layout 2 sees
    `look="art"`; `_core.PIXEL_LAYOUTS`)."""
    recipe = payload["recipe"]
    options = dict(recipe.get("env_options", {}))
    if recipe["obs_type"] == "features":
        return options
    return {**_core.PIXEL_LAYOUTS.get(payload.get("pixels_version", 1), {}), **options}


def load(path: Path, what: str | None = None) -> Model:
    """Reads and checks a model file (:func:`read_checkpoint`, then :func:`from_payload`)."""
    what = what or f"model file {str(path)!r}"
    return from_payload(read_checkpoint(Path(path), what), what)
