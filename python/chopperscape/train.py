"""PPO for ChopperScape: the training recipe, in one file (CleanRL-style, PyTorch on the CPU).

Run it with ``python -m chopperscape.train --steps 15000000 --out runs/ppo`` once the package and torch are installed.
It steps the native :class:`chopperscape.VectorEnv` (one Rust call per batch), normalises observations with
running statistics and rewards by the running standard deviation of the discounted return (the two things that made
the difference: see ``docs/learning.md``), and writes as it goes:

- ``OUT/progress.csv``: one row per update (see :data:`CSV_COLUMNS`): the return and length of the last 100
  finished episodes (empty until one has ended) (the format ``python -m chopperscape.plot`` draws), the update's diagnostics (learning rate,
  policy entropy, approximate KL, clip fraction, explained variance, value and policy losses) and how the episodes
  that ended during the update ended (shares of ``bird``, ``fuel`` and ``limit``, the 10,000-step truncation);
- ``OUT/model.pt``: the policy, its observation statistics and the options it was trained on, loadable by
  ``python -m chopperscape.evaluate OUT/model.pt``. It is saved at every checkpoint interval, at the end and on
  Ctrl-C. It holds tensors and plain data only, so it is read with ``torch.load(weights_only=True)``.

Training seeds are ``seed, seed + 1, …`` (one per env); evaluate on other seeds (``evaluate --seed 1000000``).

Runs are reproducible: every schedule (the learning rate) follows env steps over the step budget ``--steps``, never
the wall clock, so the same seed and budget give the same curve on any host; ``--minutes`` only stops a run early.
A folder that already holds a run is refused unless ``--force`` (which starts the run over in it). Every setting is
checked before anything is written; a loss that is not finite stops the run before the optimiser step, so the saved
model is never a NaN one. Ctrl-C (SIGINT, SIGTERM, SIGHUP) stops the run after the current update, saves the model
reached so far atomically, and exits with 130, 143, 129.
``--seeds 0-9`` trains several seeds and reports them as the field does (see :mod:`chopperscape.seeds`).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from collections import deque
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
from gymnasium.wrappers.utils import RunningMeanStd as _GymRunningMeanStd

try:
    import torch
    from torch import nn
except ImportError as err:  # pragma: no cover - exercised only without torch
    raise ImportError(
        "chopperscape.train needs PyTorch: pip install torch (the CPU build is enough)"
    ) from err

from . import FEATURES_VERSION, PIXELS_VERSION, _signals, progress
from ._checks import check_bool, number_in, pilot_seed, positive_int
from ._cli import ENV_OPTIONS, env_options, print_line
from .vector import VectorEnv

#: Columns of the progress CSV (the schema and its meaning: :mod:`chopperscape.progress`).
CSV_COLUMNS = list(progress.COLUMNS)

#: The recipe's settings that the command line exposes as flags (``--num-envs`` …).
RECIPE_FLAGS = (
    "obs_type", "num_envs", "num_steps", "gamma", "gae_lambda", "learning_rate", "update_epochs", "num_minibatches",
    "clip_coef", "ent_coef", "vf_coef", "max_grad_norm", "hidden", "seed", "torch_threads", "env_threads", "network",
    "device",
)

#: Recipe presets (``--preset NAME``): the settings that differ from :class:`Recipe`'s defaults; flags given on
#: the command line win. ``pixels`` learns from 84×84 grayscale frames, 4 stacked, each action held for 4 frames
#: (env steps then count decisions: a decision is 4 frames); γ = 0.996 per decision is the features recipe's
#: 0.999 per frame (0.999⁴), the same horizon in game time. See docs/learning.md for how it was chosen.
PRESETS: dict[str, dict[str, Any]] = {
    "features": {},
    "pixels": {
        "obs_type": "grayscale",
        "env_options": {"obs_size": [84, 84], "frame_stack": 4, "frame_skip": 4},
        "network": "small",
        "num_envs": 32,
        "num_steps": 128,
        "num_minibatches": 4,
        "gamma": 0.996,
        "learning_rate": 2.5e-4,
    },
}
#: The pixel recipe with a batch sized for a GPU (`--preset pixels-large --device cuda`): 8× the envs, so that each
#: forward pass and each of the 8 minibatches (4,096 samples) keeps a GPU busy; the same samples per update per env.
PRESETS["pixels-large"] = {**PRESETS["pixels"], "num_envs": 256, "num_minibatches": 8, "env_threads": 2}

#: The step budget of the recipe's figures (README, docs/learning.md): 30 minutes of one quiet core.
DEFAULT_STEPS = 15_000_000


@dataclass
class Recipe:
    """Hyperparameters of the recipe; the defaults are the ones the README's figures come from."""

    obs_type: str = "features"
    env_options: dict[str, Any] = field(default_factory=dict)
    num_envs: int = 64
    num_steps: int = 256
    gamma: float = 0.999
    gae_lambda: float = 0.95
    learning_rate: float = 3e-4
    anneal_lr: bool = True
    update_epochs: int = 4
    num_minibatches: int = 8
    clip_coef: float = 0.2
    ent_coef: float = 0.01
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5
    hidden: int = 128
    #: The network: "mlp" (features) or a CNN for pixel observations, "small" (Mnih et al. 2013's two
    #: convolutions) or "nature" (Mnih et al. 2015's three); "auto" picks "mlp" or "small" by obs_type.
    network: str = "auto"
    #: Where the network runs: "cpu", or "cuda" where torch sees a GPU (see docs/learning.md for throughput).
    device: str = "cpu"
    norm_obs: bool = True
    norm_reward: bool = True
    seed: int = 0
    torch_threads: int = 1
    env_threads: int = 1
    #: The step budget: the learning rate anneals linearly to 5 % over it.
    total_steps: int = DEFAULT_STEPS


#: `--option` names the recipe sets itself, and what to use instead.
RESERVED_OPTIONS = {
    "obs_type": "the observation is the recipe's --obs-type",
    "num_threads": "the env's threads are the recipe's --env-threads",
    "copy": "the recipe reads each step's arrays itself",
    "autoreset_mode": "the recipe steps the batch in NEXT_STEP mode and masks the reset steps",
    "render_mode": "the recipe draws nothing",
}
#: The files of a run in its folder.
RUN_FILES = ("model.pt", "progress.csv", "recipe.json")
#: The networks `Recipe.network` names.
NETWORKS = ("auto", "mlp", "small", "nature")


def check_device(device: Any) -> None:
    """`ValueError` unless `device` names a torch device that this process can use ('cpu', 'cuda', 'cuda:1', 'mps')."""
    allowed = "allowed a torch device such as 'cpu', 'cuda', 'cuda:0'"
    if not isinstance(device, str) or not device:
        raise ValueError(f"invalid value {device!r} for option `device`: {allowed}")
    try:
        d = torch.device(device)
    except (RuntimeError, ValueError):
        raise ValueError(f"invalid value {device!r} for option `device`: {allowed}") from None
    if d.type == "cuda":
        if not torch.cuda.is_available():
            raise ValueError(f"device {device!r}: torch sees no CUDA GPU here (torch.cuda.is_available() is False; "
                             "a CPU-only torch build, or no driver): use --device cpu")
        if d.index is not None and d.index >= torch.cuda.device_count():
            raise ValueError(f"device {device!r}: torch sees {torch.cuda.device_count()} CUDA GPU(s)")
    elif d.type == "mps" and not torch.backends.mps.is_available():
        raise ValueError(f"device {device!r}: torch sees no MPS device here: use --device cpu")
    elif d.type not in ("cpu", "cuda", "mps"):
        raise ValueError(f"invalid value {device!r} for option `device`: {allowed} (or 'mps')")


def check_recipe(recipe: Recipe) -> None:
    """`ValueError` naming the first setting of `recipe` that is out of range (before anything is written)."""
    r = recipe
    for name in ("num_envs", "num_steps", "update_epochs", "num_minibatches", "total_steps"):
        positive_int(name, getattr(r, name))
    positive_int("hidden", r.hidden, maximum=1 << 16)
    positive_int("torch_threads", r.torch_threads, maximum=1024)
    positive_int("env_threads", r.env_threads, maximum=1024)
    if r.num_minibatches * 4 > r.num_envs * r.num_steps:
        raise ValueError(
            f"invalid value {r.num_minibatches} for option `num_minibatches`: each minibatch needs at least 4 of the "
            f"num_envs × num_steps = {r.num_envs * r.num_steps} steps of an update (allowed 1..="
            f"{r.num_envs * r.num_steps // 4})"
        )
    number_in("gamma", r.gamma, 0.0, 1.0, low_open=True)
    number_in("gae_lambda", r.gae_lambda, 0.0, 1.0)
    number_in("learning_rate", r.learning_rate, 0.0, 1.0, low_open=True)
    number_in("clip_coef", r.clip_coef, 0.0, 10.0, low_open=True)
    number_in("ent_coef", r.ent_coef, 0.0, 1000.0)
    number_in("vf_coef", r.vf_coef, 0.0, 1000.0)
    number_in("max_grad_norm", r.max_grad_norm, 0.0, 1e9, low_open=True)
    pilot_seed(r.seed)
    for name in ("anneal_lr", "norm_obs", "norm_reward"):
        check_bool(name, getattr(r, name))
    if not isinstance(r.obs_type, str):
        raise ValueError(f"invalid value {r.obs_type!r} for option `obs_type`: allowed a string")
    if r.network not in NETWORKS:
        raise ValueError(f"invalid value {r.network!r} for option `network`: allowed {', '.join(map(repr, NETWORKS))}")
    check_device(r.device)
    if not isinstance(r.env_options, dict):
        raise ValueError(f"invalid value {r.env_options!r} for option `env_options`: allowed a dict of env options")
    for name in r.env_options:
        if name in RESERVED_OPTIONS:
            raise ValueError(f"env option `{name}` is not taken: {RESERVED_OPTIONS[name]}")
        if name not in ENV_OPTIONS:
            raise ValueError(f"unknown env option `{name}`: allowed {', '.join(ENV_OPTIONS)}")


def check_minutes(minutes: float | None) -> None:
    """`ValueError` unless `minutes` (the wall-clock stop) is None or positive and finite."""
    if minutes is not None:
        number_in("minutes", minutes, 0.0, 1e7, low_open=True)


def check_run_folder(out: Path, force: bool = False) -> None:
    """`ValueError` when `out` cannot hold a new run: it is not a folder, or it holds a run (`RUN_FILES`) and not
    `force`. Nothing is written."""
    out = Path(out)
    if os.path.lexists(out) and not out.is_dir():
        raise ValueError(f"--out {out} is not a folder: give a folder for progress.csv, model.pt and recipe.json")
    there = [name for name in RUN_FILES if os.path.lexists(out / name)]
    if there and not force:
        raise ValueError(
            f"--out {out} already holds a run ({', '.join(there)}): pass --force to start over in it (its files are "
            "replaced), or give another folder"
        )


class RunningMeanStd(_GymRunningMeanStd):
    """Gymnasium's running mean and variance (Chan et al.'s parallel update, the one its and SB3's normalisers keep),
    with its state as plain data for checkpoints."""

    def __init__(self, shape: tuple[int, ...] = ()):
        super().__init__(shape=shape)

    def state(self) -> dict[str, Any]:
        return {"mean": self.mean.tolist(), "var": self.var.tolist(), "count": float(self.count)}

    @classmethod
    def from_state(cls, s: dict[str, Any]) -> RunningMeanStd:
        r = cls()
        r.mean, r.var, r.count = np.asarray(s["mean"]), np.asarray(s["var"]), float(s["count"])
        return r


class ObsNormalizer:
    """Standardises observations with running statistics, clipped to ±10 (frozen at evaluation)."""

    def __init__(self, shape: tuple[int, ...], enabled: bool = True):
        self.rms = RunningMeanStd(shape)
        self.enabled = enabled

    def __call__(self, obs: np.ndarray, update: bool = False) -> np.ndarray:
        obs = obs.astype(np.float32, copy=False)
        if not self.enabled:
            return obs
        if update:
            self.rms.update(obs)
        out = (obs - self.rms.mean) / np.sqrt(self.rms.var + 1e-8)
        return np.clip(out, -10.0, 10.0).astype(np.float32)


#: A layer that `_layer` initialises.
_L = TypeVar("_L", nn.Linear, nn.Conv2d)


def _layer(layer: _L, std: float = math.sqrt(2)) -> _L:
    """Orthogonal weights and zero biases, as in CleanRL's PPO."""
    nn.init.orthogonal_(layer.weight, std)
    if layer.bias is not None:
        nn.init.constant_(layer.bias, 0.0)
    return layer


class ActorCritic(nn.Module):
    """What PPO needs of a network: `actor(obs)` gives the action logits and `critic(obs)` the value."""

    actor: nn.Module
    critic: nn.Module

    def value(self, x: torch.Tensor) -> torch.Tensor:
        return self.critic(x).squeeze(-1)

    def act(self, x: torch.Tensor, action: torch.Tensor | None = None):
        """`(action, log-probability, entropy, value)`; the action is sampled unless given."""
        logits = self.actor(x)
        dist = torch.distributions.Categorical(logits=logits)
        if action is None:
            action = dist.sample()
        return action, dist.log_prob(action), dist.entropy(), self.value(x)


class Agent(ActorCritic):
    """Separate actor and critic MLPs (tanh), orthogonal init as in CleanRL's PPO."""

    def __init__(self, obs_dim: int, num_actions: int, hidden: int):
        super().__init__()
        self.critic = nn.Sequential(
            _layer(nn.Linear(obs_dim, hidden)), nn.Tanh(), _layer(nn.Linear(hidden, hidden)), nn.Tanh(),
            _layer(nn.Linear(hidden, 1), 1.0),
        )
        self.actor = nn.Sequential(
            _layer(nn.Linear(obs_dim, hidden)), nn.Tanh(), _layer(nn.Linear(hidden, hidden)), nn.Tanh(),
            _layer(nn.Linear(hidden, num_actions), 0.01),
        )


class Frames(nn.Module):
    """The env's grayscale observation as the convolutions want it: ``(N, H, W)`` or ``(N, H, W, k)`` (k stacked
    frames, uint8 or float in 0..255) to ``(N, k, H, W)`` floats in [0, 1]. Part of the network, so that a
    saved or exported policy takes the env's observation unchanged."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = x.float() * (1.0 / 255.0)
        return x.unsqueeze(1) if x.dim() == 3 else x.permute(0, 3, 1, 2)


#: CNN layouts: (channels, kernel, stride) per convolution, then the width of the dense layer. "small" on frames
#: under 64 pixels starts with a 4×4 stride-2 convolution, so that its second one sees the same 9×9 map at 42×42
#: as at 84×84.
CNNS = {
    "nature": ([(32, 8, 4), (64, 4, 2), (64, 3, 1)], 512),
    "small": ([(16, 8, 4), (32, 4, 2)], 256),
    "small-42": ([(16, 4, 2), (32, 4, 2)], 256),
}


class CnnAgent(ActorCritic):
    """Actor and critic heads on one shared CNN trunk (the Atari PPO layout of CleanRL and SB3's CnnPolicy).
    `actor(obs)` gives the logits and `critic(obs)` the value, as for :class:`Agent`."""

    def __init__(self, obs_shape: tuple[int, ...], num_actions: int, network: str):
        super().__init__()
        h, w = obs_shape[:2]
        stack = obs_shape[2] if len(obs_shape) == 3 else 1
        name = "small-42" if network == "small" and min(h, w) < 64 else network
        convs, width = CNNS[name]
        layers: list[nn.Module] = [Frames()]
        channels = stack
        for out, kernel, stride in convs:
            layers += [_layer(nn.Conv2d(channels, out, kernel, stride)), nn.ReLU()]
            channels = out
        layers.append(nn.Flatten())
        size = [h, w]
        for _, kernel, stride in convs:
            size = [(d - kernel) // stride + 1 for d in size]
            if min(size) < 1:
                raise ValueError(
                    f"frames of {h}×{w} are too small for the {network!r} network (at least 36×36 for 'nature', "
                    "16×16 for 'small')"
                )
        flat = channels * size[0] * size[1]
        trunk = nn.Sequential(*layers, _layer(nn.Linear(flat, width)), nn.ReLU())
        self.actor = nn.Sequential(trunk, _layer(nn.Linear(width, num_actions), 0.01))
        self.critic = nn.Sequential(trunk, _layer(nn.Linear(width, 1), 1.0))


def network_of(recipe: dict[str, Any] | Recipe) -> str:
    """The network a recipe trains: its `network`, with "auto" resolved by its obs_type."""
    r = recipe if isinstance(recipe, dict) else asdict(recipe)
    net = r.get("network", "mlp")
    if net == "auto":
        return "mlp" if r["obs_type"] == "features" else "small"
    return net


def build_agent(
    network: str, obs_shape: tuple[int, ...], num_actions: int = 5, hidden: int = 128
) -> ActorCritic:
    """The agent for `network` ("mlp", "small" or "nature") on observations of `obs_shape` (one env's)."""
    if network == "mlp":
        if len(obs_shape) != 1:
            raise ValueError(f"the mlp network takes vector observations (obs_type='features'), not shape {obs_shape}")
        return Agent(int(obs_shape[0]), num_actions, hidden)
    if network not in ("small", "nature"):
        raise ValueError(f"invalid network {network!r}: allowed 'auto', 'mlp', 'small', 'nature'")
    if len(obs_shape) not in (2, 3):
        raise ValueError(f"the {network!r} CNN takes grayscale frames (obs_type='grayscale'), not shape {obs_shape}")
    return CnnAgent(tuple(obs_shape), num_actions, network)


def agent_from_checkpoint(payload: Any, what: str = "the checkpoint") -> ActorCritic:
    """Rebuilds the agent a checkpoint (see :func:`save`) holds, with its weights, in eval mode. `ValueError`
    naming the first field that is missing or of the wrong kind, or a layout version other than this package's."""

    def bad(field: str, expected: str) -> ValueError:
        return ValueError(f"{what} is not a usable chopperscape.train model: `{field}` {expected}")

    if not isinstance(payload, dict) or payload.get("format") != "chopperscape-ppo/1":
        raise ValueError(f"{what} is not a chopperscape.train model (format chopperscape-ppo/1)")
    recipe = payload.get("recipe")
    if not isinstance(recipe, dict) or not isinstance(recipe.get("env_options", {}), dict):
        raise bad("recipe", "must be the recipe's settings (a dict with env_options)")
    obs_dim, hidden = payload.get("obs_dim"), recipe.get("hidden")
    for field, value in (("obs_dim", obs_dim), ("recipe.hidden", hidden), ("num_actions", payload.get("num_actions"))):
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 1 << 24:
            raise bad(field, "must be a positive integer")
    if payload["num_actions"] != 5 or not isinstance(recipe.get("obs_type"), str):
        raise bad("num_actions/recipe.obs_type", "must be 5 actions and an observation type")
    shape = payload.get("obs_shape", [obs_dim])
    if (
        not isinstance(shape, list) or not 1 <= len(shape) <= 3
        or not all(isinstance(d, int) and not isinstance(d, bool) and 1 <= d <= 4096 for d in shape)
        or math.prod(shape) != obs_dim
    ):
        raise bad("obs_shape", f"must be 1 to 3 sizes in 1..=4096 whose product is obs_dim ({obs_dim})")
    pixels = recipe["obs_type"] != "features"
    learned = payload.get("pixels_version" if pixels else "features_version", 1 if pixels else 2)
    current = PIXELS_VERSION if pixels else FEATURES_VERSION
    if learned != current:
        kind = "pixel" if pixels else "features"
        raise ValueError(
            f"{what}: the model learned {kind} layout v{learned}, and this chopperscape draws v{current}: retrain "
            "it, or use the chopperscape version it was trained with"
        )
    network = network_of(recipe)
    try:
        agent = build_agent(network, tuple(shape), 5, int(hidden or 0))
    except ValueError as e:
        raise bad("recipe.network", str(e)) from None
    for part in ("actor", "critic"):
        state = payload.get(part)
        if not isinstance(state, dict) or not all(isinstance(v, torch.Tensor) for v in state.values()):
            raise bad(part, "must be a dict of tensors")
        try:
            getattr(agent, part).load_state_dict(state)
        except RuntimeError as e:
            raise bad(part, f"does not fit the {network} network on observations of shape {tuple(shape)}: "
                            f"{str(e).splitlines()[0]}") from None
    return agent.eval()


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
        "format": "chopperscape-ppo/1",
        "recipe": _plain(asdict(recipe)),
        "obs_shape": list(obs_shape),
        "obs_dim": int(np.prod(obs_shape)),
        "num_actions": 5,
        "obs_rms": obs_norm.rms.state() if obs_norm.enabled else None,
        "env_steps": int(env_steps),
        # The observation layouts the policy learned: a later layout is a different input.
        "features_version": FEATURES_VERSION,
        "pixels_version": PIXELS_VERSION,
        # Not cloned: a CNN's trunk, in both state dicts, then shares its storage and is written once.
        "actor": {k: v.detach().cpu() for k, v in agent.actor.state_dict().items()},
        "critic": {k: v.detach().cpu() for k, v in agent.critic.state_dict().items()},
    }
    tmp = path.with_name(f".{path.name}.{os.getpid()}.part")
    with _signals.deferred(f"the model is saved in {path}"):
        try:
            torch.save(payload, tmp)
            os.replace(tmp, path)
        finally:
            if os.path.lexists(tmp):
                os.unlink(tmp)


def train(recipe: Recipe, out: Path, minutes: float | None = None, force: bool = False) -> Path:
    """Runs PPO for `recipe.total_steps` env steps, or until `minutes` of wall time if that comes first (the
    schedules still follow `recipe.total_steps`, so a run cut short is the prefix of the full one); returns the
    model path. `ValueError` for a setting out of range or a folder that holds a run (unless `force`), before
    anything is written; `_signals.Interrupted` after a signal, once the model reached so far is saved."""
    out = Path(out)
    check_recipe(recipe)
    check_minutes(minutes)
    check_run_folder(out, force)
    torch.manual_seed(recipe.seed)
    torch.set_num_threads(recipe.torch_threads)
    rng = np.random.default_rng(recipe.seed)

    envs = VectorEnv(
        recipe.num_envs, num_threads=recipe.env_threads, obs_type=recipe.obs_type, **recipe.env_options
    )
    obs_shape = tuple(envs.single_observation_space.shape or ())
    network = network_of(recipe)
    device = torch.device(recipe.device)
    agent = build_agent(network, obs_shape, 5, recipe.hidden).to(device)
    optimizer = torch.optim.Adam(agent.parameters(), lr=recipe.learning_rate, eps=1e-5)
    # Vector observations are standardised with running statistics; frames are scaled by the network itself.
    pixels = network != "mlp"
    obs_norm = ObsNormalizer(obs_shape, recipe.norm_obs and not pixels)
    ret_rms = RunningMeanStd(())
    disc_return = np.zeros(recipe.num_envs)

    def encode(raw: np.ndarray) -> torch.Tensor:
        """A batch of observations as the network takes them (frames stay uint8: a quarter of the memory)."""
        return torch.from_numpy(raw if pixels else obs_norm(raw, update=True)).to(device)

    # --- Rollout storage -------------------------------------------------------------------------------------
    n, t_len = recipe.num_envs, recipe.num_steps
    buf_obs = torch.zeros((t_len, n, *obs_shape), dtype=torch.uint8 if pixels else torch.float32, device=device)
    buf_act = torch.zeros((t_len, n), dtype=torch.long, device=device)
    buf_logp, buf_rew, buf_done, buf_val = (torch.zeros((t_len, n), device=device) for _ in range(4))
    # With NEXT_STEP autoreset, the step after an episode's end is the reset step: no transition to learn from.
    buf_valid = torch.zeros((t_len, n), device=device)

    raw, _ = envs.reset(seed=recipe.seed)
    next_obs = encode(raw)
    next_done = np.zeros(n, bool)  # the previous step ended an episode: this step is a reset step
    ep_return, ep_len = np.zeros(n), np.zeros(n, np.int64)
    finished: deque[tuple[float, int]] = deque(maxlen=100)
    episodes = 0
    env_steps = 0
    start = time.monotonic()
    model_path = out / "model.pt"
    csv_path = out / "progress.csv"
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "recipe.json", "w") as f:
        json.dump(asdict(recipe), f, indent=2)
    writer = progress.Writer(csv_path)
    update = 0
    stop = _signals.defer()  # Ctrl-C ends the run after the current update, which is then saved
    try:
        while env_steps < recipe.total_steps:
            if stop.pending is not None:
                break
            if minutes is not None and time.monotonic() - start >= minutes * 60:
                break
            # The learning rate follows env steps only: the same run on a busy host is the same run.
            lr = recipe.learning_rate
            if recipe.anneal_lr:
                lr *= max(1.0 - env_steps / recipe.total_steps, 0.05)
            optimizer.param_groups[0]["lr"] = lr

            # --- Rollout ---------------------------------------------------------------------------------------
            ends = {"bird": 0, "fuel": 0, "limit": 0}
            for t in range(t_len):
                valid = ~next_done
                with torch.no_grad():
                    action, logp, _, value = agent.act(next_obs)
                buf_obs[t], buf_act[t], buf_logp[t], buf_val[t] = next_obs, action, logp, value
                buf_valid[t] = torch.from_numpy(valid.astype(np.float32)).to(device)
                raw, reward, term, trunc, info = envs.step(action.cpu().numpy())
                env_steps += int(valid.sum())
                done = term | trunc
                # Episode statistics, on real (not reset) steps.
                ep_return += np.where(valid, reward, 0)
                ep_len += valid
                for i in np.flatnonzero(done):
                    finished.append((float(ep_return[i]), int(ep_len[i])))
                    episodes += 1
                    ends[str(info["cause"][i]) if term[i] else "limit"] += 1
                ep_return[done], ep_len[done] = 0, 0
                # Reward scaling by the std of the discounted return (Gymnasium's NormalizeReward).
                r = reward.astype(np.float64)
                if recipe.norm_reward:
                    disc_return = np.where(valid, disc_return * recipe.gamma + r, 0.0)
                    if valid.any():
                        ret_rms.update(disc_return[valid])
                    r = r / math.sqrt(ret_rms.var + 1e-8)
                    disc_return[done] = 0.0
                buf_rew[t] = torch.from_numpy(np.where(valid, r, 0.0).astype(np.float32)).to(device)
                # Truncation is treated as termination (10,000 steps is ten horizons of γ = 0.999).
                buf_done[t] = torch.from_numpy(done.astype(np.float32)).to(device)
                next_done = done
                next_obs = encode(raw)

            # --- Advantages: GAE over valid steps; a reset step neither bootstraps nor is learned from ------------
            with torch.no_grad():
                next_value = agent.value(next_obs)
                adv = torch.zeros((t_len, n), device=device)
                last = torch.zeros(n, device=device)
                for t in reversed(range(t_len)):
                    nv = next_value if t == t_len - 1 else buf_val[t + 1]
                    nonterminal = 1.0 - buf_done[t]
                    delta = buf_rew[t] + recipe.gamma * nv * nonterminal - buf_val[t]
                    last = delta + recipe.gamma * recipe.gae_lambda * nonterminal * last
                    # The row after an episode's end is its reset step: it carries nothing across.
                    last = last * buf_valid[t]
                    adv[t] = last
                returns = adv + buf_val
            mask = buf_valid.reshape(-1).bool()
            b_obs = buf_obs.reshape(-1, *obs_shape)[mask]
            b_act, b_logp = buf_act.reshape(-1)[mask], buf_logp.reshape(-1)[mask]
            b_adv, b_ret = adv.reshape(-1)[mask], returns.reshape(-1)[mask]
            b_val = buf_val.reshape(-1)[mask]
            size = b_obs.shape[0]

            # --- Optimisation ------------------------------------------------------------------------------------
            stats = np.zeros(6)  # entropy, approx_kl, clip_frac, value_loss, policy_loss, minibatches
            for _ in range(recipe.update_epochs):
                # Even minibatches (no tiny remainder, whose advantage std would be undefined).
                for idx in torch.from_numpy(rng.permutation(size)).to(device).tensor_split(recipe.num_minibatches):
                    _, logp, entropy, value = agent.act(b_obs[idx], b_act[idx])
                    log_ratio = logp - b_logp[idx]
                    ratio = log_ratio.exp()
                    a = b_adv[idx]
                    a = (a - a.mean()) / (a.std() + 1e-8)
                    pg = torch.max(-a * ratio, -a * ratio.clamp(1 - recipe.clip_coef, 1 + recipe.clip_coef)).mean()
                    v_loss = 0.5 * ((value - b_ret[idx]) ** 2).mean()
                    ent = entropy.mean()
                    loss = pg - recipe.ent_coef * ent + recipe.vf_coef * v_loss
                    if not torch.isfinite(loss):
                        raise FloatingPointError(f"loss became {loss.item()} at update {update}")
                    optimizer.zero_grad()
                    loss.backward()
                    nn.utils.clip_grad_norm_(agent.parameters(), recipe.max_grad_norm)
                    optimizer.step()
                    with torch.no_grad():
                        # Schulman's low-variance KL estimator, as CleanRL logs it.
                        kl = ((ratio - 1) - log_ratio).mean()
                        clipped = ((ratio - 1).abs() > recipe.clip_coef).float().mean()
                    stats += [ent.item(), kl.item(), clipped.item(), v_loss.item(), pg.item(), 1]
            update += 1
            var_ret = b_ret.var().item()
            explained = float("nan") if var_ret == 0 else 1 - (b_ret - b_val).var().item() / var_ret

            # --- Logging -----------------------------------------------------------------------------------------
            # One row per update; the return columns stay empty until the first episode has ended.
            rets = np.array([r for r, _ in finished])
            lens = np.array([l for _, l in finished])
            ended = sum(ends.values())
            m = stats[:5] / max(stats[5], 1)
            row = {"env_steps": env_steps, "wall_s": f"{time.monotonic() - start:.1f}", "episodes": episodes,
                   "learning_rate": f"{lr:.6g}", "entropy": f"{m[0]:.4f}", "approx_kl": f"{m[1]:.5f}",
                   "clip_frac": f"{m[2]:.4f}", "explained_var": f"{explained:.4f}", "value_loss": f"{m[3]:.5f}",
                   "policy_loss": f"{m[4]:.5f}", "ended": ended}
            if finished:
                row.update(mean_return=f"{rets.mean():.1f}", std_return=f"{rets.std():.1f}",
                           mean_length=f"{lens.mean():.1f}")
            if ended:
                row.update({k: f"{ends[k] / ended:.3f}" for k in ("bird", "fuel", "limit")})
            writer.row(row)
            if update % 50 == 0:
                save(model_path, agent, obs_norm, recipe, obs_shape, env_steps)
    finally:
        writer.close()
        envs.close()
        stop.restore()
    save(model_path, agent, obs_norm, recipe, obs_shape, env_steps)
    stop.check(f"the model reached so far ({env_steps} env steps) is saved in {model_path}")
    return model_path


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if any(x == "--seeds" or x.startswith("--seeds=") for x in args):
        # Several seeds, evaluated and summarised: the runner takes its own flags and passes the rest back here.
        from . import seeds

        return seeds.main(args)
    p = argparse.ArgumentParser(prog="python -m chopperscape.train", description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, required=True,
                   help="folder for progress.csv, model.pt, recipe.json (with --seeds: one sub-folder per seed)")
    p.add_argument("--steps", type=int, default=DEFAULT_STEPS,
                   help=f"env-step budget; the learning rate anneals over it (default {DEFAULT_STEPS:,})")
    p.add_argument("--minutes", type=float, default=None,
                   help="stop after this much wall time (only stops: the schedule still follows --steps)")
    p.add_argument("--seeds", default=None, metavar="LIST",
                   help="train these seeds (e.g. 0-9 or 0,3,5), evaluate each on held-out seeds and write a summary "
                   "(runs python -m chopperscape.seeds, which documents its own flags: --jobs, --eval-episodes, ...)")
    p.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                   help="an env option, e.g. --option frame_skip=4 (JSON values)")
    p.add_argument("--preset", choices=sorted(PRESETS), default="features",
                   help="recipe preset: features (the default), pixels (grayscale frames, a CNN) or pixels-large (the same with 256 envs, for --device cuda); flags override it")
    defaults = Recipe()
    for f in RECIPE_FLAGS:
        p.add_argument(f"--{f.replace('_', '-')}", type=type(getattr(defaults, f)), default=None,
                       help=f"default {getattr(defaults, f)!r} (or the preset's)")
    p.add_argument("--no-norm-obs", action="store_true")
    p.add_argument("--no-norm-reward", action="store_true")
    p.add_argument("--force", action="store_true", help="start over in an --out folder that already holds a run")
    a = p.parse_args(args)
    preset = dict(PRESETS[a.preset])
    allowed = [n for n in ENV_OPTIONS if n not in RESERVED_OPTIONS]
    options = {**preset.pop("env_options", {}), **env_options(p, a.option, allowed=allowed, refused=RESERVED_OPTIONS)}
    settings = {**{f: getattr(defaults, f) for f in RECIPE_FLAGS}, **preset}
    settings.update({f: getattr(a, f) for f in RECIPE_FLAGS if getattr(a, f) is not None})
    recipe = Recipe(
        **settings, env_options=options, norm_obs=not a.no_norm_obs, norm_reward=not a.no_norm_reward,
        total_steps=a.steps,
    )
    try:
        check_recipe(recipe)
        check_minutes(a.minutes)
        check_run_folder(a.out, a.force)
    except ValueError as e:
        p.error(str(e))
    try:
        path = train(recipe, a.out, a.minutes, force=a.force)
    except ValueError as e:  # an env option the env refuses
        print(f"error: {e}", file=sys.stderr)
        return 2
    except FloatingPointError as e:
        print(f"error: training stopped: {e}; the model saved last is kept", file=sys.stderr)
        return 1
    except _signals.Interrupted as e:
        print(e, file=sys.stderr)
        return e.exit_code
    return print_line(json.dumps({"model": str(path), "progress": str(a.out / "progress.csv")}))


if __name__ == "__main__":
    sys.exit(main())
