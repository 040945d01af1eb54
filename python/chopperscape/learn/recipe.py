"""The PPO recipe's settings: :class:`Recipe` (the hyperparameters docs/results.md's figures come from), the presets
``--preset`` names (:mod:`.presets`, re-exported here), and the checks that refuse a setting before anything is
written.

Plain data, no torch at import: :mod:`chopperscape.learn.seeds` and the command lines read the defaults without
loading a network library (only :func:`check_device` imports torch, to ask it which devices exist).
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

from .._checks import check_bool, number_in, policy_seed, positive_int
from ..options import ENV_OPTIONS
from .presets import PRESETS as PRESETS  # re-exported: the command lines and examples read it here

#: The recipe's settings that the command line exposes as flags (``--num-envs`` …).
RECIPE_FLAGS = (
    "obs_type",
    "num_envs",
    "num_steps",
    "gamma",
    "gae_lambda",
    "learning_rate",
    "lr_floor",
    "update_epochs",
    "num_minibatches",
    "clip_coef",
    "ent_coef",
    "ent_floor",
    "vf_coef",
    "max_grad_norm",
    "hidden",
    "seed",
    "torch_threads",
    "env_threads",
    "network",
    "device",
    "aux_coef",
    "augment",
    "teacher",
    "teacher_coef",
    "teacher_fade",
    "torch_compile",
    "recon_coef",
    "rnd_coef",
    "rnd_own_value",
    "rnd_proportion",
    "rnd_pool",
    "rnd_floor",
    "rnd_hold",
)


#: The largest model file the tools read (`evaluate`, `export`, `--teacher`): the pixel recipe's is 2.7 MB. A recipe
#: model's claimed network must also fit the weights it holds before it is built (`modelfile.agent_from_checkpoint`).
MAX_MODEL_BYTES = 1 << 30

#: The widest MLP the recipe trains (`hidden`), and the largest step budget (`--steps`; years of CPU).
MAX_HIDDEN = 4096
MAX_TOTAL_STEPS = 10**12
#: The most memory the rollout buffers of one update may take (`num_envs` x `num_steps` observations and their
#: numbers), checked once the observation's size is known, before anything is allocated or written.
MAX_ROLLOUT_BYTES = 8 << 30
#: The most parameters a network may have (1 GiB of float32 weights; the pixel recipe's CNN has 0.7 million).
MAX_PARAMETERS = 1 << 28

#: The learning rate's schedule over a step budget of T (`Recipe.anneal_lr`): the rate times max(1 - t / T, LR_FLOOR),
#: a linear decay that stops at 5 % of the rate at 0.95 T. The SB3 and RLlib examples follow the same schedule.
#: `Recipe.lr_floor` (`--lr-floor`) sets another floor for a run.
LR_FLOOR = 0.05

#: The step budget of the recipe's figures (docs/results.md, docs/learning.md): 30 minutes of one quiet core. A
#: preset may carry its own (`total_steps`); `--steps` wins over both.
DEFAULT_STEPS = 15_000_000


@dataclass
class Recipe:
    """Hyperparameters of the recipe; the defaults are the ones docs/results.md's figures come from."""

    obs_type: str = "features"
    env_options: dict[str, Any] = field(default_factory=dict)
    num_envs: int = 64
    num_steps: int = 256
    #: 0.9995 and entropy 0.02: the setting that trained all ten seeds of the benchmark past the heuristic
    #: (docs/notes/training-seeds.md); 0.999 and 0.01 stalled two seeds in five on refuelling.
    gamma: float = 0.9995
    gae_lambda: float = 0.95
    learning_rate: float = 3e-4
    anneal_lr: bool = True
    #: Where the annealed rate stops, as a fraction of `learning_rate`: the rate times max(1 − t / T, lr_floor).
    #: 1 keeps it constant; 0 anneals it to nothing at `total_steps`.
    lr_floor: float = LR_FLOOR
    update_epochs: int = 4
    num_minibatches: int = 8
    clip_coef: float = 0.2
    ent_coef: float = 0.02
    #: Where the entropy weight ends, as a fraction of `ent_coef`: it falls linearly over the step budget T, the
    #: weight at t being ent_coef × (1 − (1 − ent_floor) · min(t / T, 1)). 1 (the default) keeps it constant: a wide
    #: search early (issue 43's stalled seed) without a noisy policy late (the strong seeds' dodging).
    ent_floor: float = 1.0
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5
    hidden: int = 128
    #: The network: "mlp" (features) or a CNN for pixel observations, "small" (Mnih et al. 2013's two
    #: convolutions) or "nature" (Mnih et al. 2015's three), actor and critic on one trunk; "small-split" is "small"
    #: with a trunk of its own for the critic (twice the convolutions); "small-coord" adds CoordConv's coordinates
    #: to its first convolution and "small-keypoints" reads its maps as keypoints (a spatial soft-argmax; both:
    #: :mod:`chopperscape.learn.networks`); "auto" picks "mlp" or "small" by obs_type.
    network: str = "auto"
    #: Where the network runs: "cpu", or "cuda" where torch sees a GPU (see docs/notes/pixels-cost.md for throughput).
    device: str = "cpu"
    norm_obs: bool = True
    norm_reward: bool = True
    seed: int = 0
    torch_threads: int = 1
    env_threads: int = 1
    #: The step budget: the learning rate anneals linearly over it, to `lr_floor` of itself.
    total_steps: int = DEFAULT_STEPS
    #: Pixel recipes only: weight of an auxiliary loss that trains the CNN's trunk to predict the game's 46
    #: `features` (standardised) from the frames, read from a twin env that the same seeds and actions keep in
    #: the same state. Only training uses it: the policy still acts on frames alone, and the saved model has no
    #: such head. 0 (the default) turns it off. See docs/notes/pixels-budget.md.
    aux_coef: float = 0.0
    #: CNN recipes only: the network reads ``1 - frame / 255`` (the white sky as 0, sprites and the gauge
    #: positive) rather than ``frame / 255``; see :class:`chopperscape.learn.networks.Frames` for why. Models of
    #: chopperscape 0.1.0 have no such setting and read plain frames.
    invert_frames: bool = True
    #: Pixel recipes only: a features model (from this trainer, on the same rules) that guides the CNN early on
    #: ("kickstarting", Schmitt et al. 2018). The loss adds `teacher_coef` × KL(teacher ‖ policy) on the policy's
    #: own rollouts (so, unlike cloning, the states are those the policy visits), the teacher reading a twin
    #: features env kept in lockstep. The weight falls linearly to 0 at `teacher_fade` × `total_steps`; from there
    #: on the run is plain PPO. Training only: the saved model is a plain pixel model. "" (the default): no teacher.
    teacher: str = ""
    teacher_coef: float = 1.0
    teacher_fade: float = 1.0
    #: CNN recipes only: data augmentation of the update's minibatches. "shift" is DrQ's and RAD's random shift
    #: (Kostrikov et al. 2020, Laskin et al. 2020): each frame stack padded by repeating its edges, by 4 pixels at
    #: 84 × 84 (scaled with the frame, at least 1), then cropped back at a random offset. "none" (the default):
    #: none. The rollout's forward passes see the frames as they are.
    augment: str = "none"
    #: CNN recipes only: the network's forward and backward run through `torch.compile` (Inductor's C++ kernels;
    #: :mod:`chopperscape.learn.compiled`), each minibatch padded to one fixed size so that it compiles once. The
    #: same learning as eager torch up to float rounding; the pixel loop 1.4 times faster on this project's CPUs
    #: (docs/notes/pixels-speed-and-probes.md). Needs a C++ compiler (`g++`, or the one `CXX` names).
    torch_compile: bool = False
    #: CNN recipes only: weight of a self-supervised loss from the frames alone, a linear decoder that
    #: reconstructs each minibatch's latest frame (at half size) from the trunk's embedding
    #: (:mod:`chopperscape.learn.selfsup`). Training only: the saved model has no decoder. 0 (the default): none.
    recon_coef: float = 0.0
    #: CNN recipes only: weight of an exploration bonus from the frames alone, Random Network Distillation's
    #: prediction error on each step's latest frame, scaled by its running spread and added to the step's reward
    #: (:mod:`chopperscape.learn.novelty`). Training only: the saved model has neither network. 0 (the default): none.
    rnd_coef: float = 0.0
    #: With `rnd_coef`: the bonus as the paper has it, a reward with a value head of its own on the trunk, its return
    #: not cut at episode ends, `rnd_coef` weighing its advantage. False (the default): added to the game's reward.
    rnd_own_value: bool = False
    #: With `rnd_coef`: the share of each minibatch the bonus's predictor learns from (CleanRL's `update_proportion`,
    #: 0.25 there): a cheaper update, a slower-learning predictor. 1.0 (the default): all of it.
    rnd_proportion: float = 1.0
    #: With `rnd_coef`: the bonus's networks read each frame with every `rnd_pool` × `rnd_pool` square of pixels
    #: averaged into one (1, 2 or 4): at 2, a 21×21 frame in place of 42×42, a sixth of their arithmetic and about
    #: half of the bonus's time (it tells the top of the sky from the bottom, which a coarser frame still shows).
    #: 1 (the default): as it is.
    rnd_pool: int = 1
    #: With `rnd_coef`: where the bonus's weight ends, as a fraction of `rnd_coef`: it falls linearly over the step
    #: budget T, the weight at t being rnd_coef × (1 − (1 − rnd_floor) · min(t / T, 1)), as `ent_floor` does the
    #: entropy's. 1 (the default) keeps it constant; 0 leaves the game's return alone to learn from at the end.
    rnd_floor: float = 1.0
    #: With `rnd_floor` below 1: the share of the step budget over which the bonus's weight holds at `rnd_coef`
    #: before it falls, linearly over the rest to `rnd_floor` × `rnd_coef`: at t the weight is
    #: rnd_coef × (1 − (1 − rnd_floor) · clamp((t / T − rnd_hold) / (1 − rnd_hold), 0, 1)). 0 (the default): it
    #: falls from the start; 0.5 searches at the full weight over the first half, then lets the game's return take over.
    rnd_hold: float = 0.0


#: The values `rnd_pool` takes: powers of two, so that each pooled pixel, a mean of bytes, is exact in float32.
RND_POOLS = (1, 2, 4)


#: Settings added after run folders with resume states existed, with the value every older run had: a recipe's hash
#: (:func:`chopperscape.learn.rundir.recipe_hash`) leaves them out at that value, so those folders still resume.
LATER_SETTINGS: dict[str, Any] = {
    "torch_compile": False,
    "recon_coef": 0.0,
    "lr_floor": LR_FLOOR,
    "rnd_coef": 0.0,
    "ent_floor": 1.0,
    "rnd_own_value": False,
    "rnd_proportion": 1.0,
    "rnd_pool": 1,
    "rnd_floor": 1.0,
    "rnd_hold": 0.0,
}

#: `--option` names the recipe sets itself, and what to use instead.
RESERVED_OPTIONS = {
    "obs_type": "the observation is the recipe's --obs-type",
    "num_threads": "the env's threads are the recipe's --env-threads",
    "copy": "the recipe reads each step's arrays itself",
    "autoreset_mode": "the recipe steps the batch in NEXT_STEP mode and masks the reset steps",
    "render_mode": "the recipe draws nothing",
}
#: The augmentations `Recipe.augment` names.
AUGMENTS = ("none", "shift")
#: The networks `Recipe.network` names.
NETWORKS = (
    "auto",
    "mlp",
    "small",
    "nature",
    "small-split",
    "small-coord",
    "small-keypoints",
    "small-coord-keypoints",
    "small-coord-deep",
    "small-coord-deep-split",
    "small-coord-deep-stem",
    "small-coord-deep-stem-conv3",
    "small-coord-deep-stem-norm",
)


def check_device(device: Any) -> None:
    """`ValueError` unless `device` names a torch device that this process can use ('cpu', 'cuda', 'cuda:1', 'mps')."""
    import torch

    allowed = "allowed a torch device such as 'cpu', 'cuda', 'cuda:0'"
    if not isinstance(device, str) or not device:
        raise ValueError(f"invalid value {device!r} for option `device`: {allowed}")
    try:
        d = torch.device(device)
    except (RuntimeError, ValueError):
        raise ValueError(f"invalid value {device!r} for option `device`: {allowed}") from None
    if d.type == "cuda":
        if not torch.cuda.is_available():
            raise ValueError(
                f"device {device!r}: torch sees no CUDA GPU here (torch.cuda.is_available() is False; "
                "a CPU-only torch build, or no driver): use --device cpu"
            )
        if d.index is not None and d.index >= torch.cuda.device_count():
            raise ValueError(f"device {device!r}: torch sees {torch.cuda.device_count()} CUDA GPU(s)")
    elif d.type == "mps" and not torch.backends.mps.is_available():
        raise ValueError(f"device {device!r}: torch sees no MPS device here: use --device cpu")
    elif d.type not in ("cpu", "cuda", "mps"):
        raise ValueError(f"invalid value {device!r} for option `device`: {allowed} (or 'mps')")


def check_recipe(recipe: Recipe) -> None:
    """`ValueError` naming the first setting of `recipe` that is out of range (before anything is written)."""
    r = recipe
    for name in ("num_envs", "num_steps", "num_minibatches"):
        positive_int(name, getattr(r, name))
    positive_int("total_steps", r.total_steps, maximum=MAX_TOTAL_STEPS)
    positive_int("update_epochs", r.update_epochs, maximum=1000)
    # Two hidden x hidden layers per network: 4096 is 2 x 64 MiB of weights, 65536 was 2 x 16 GiB.
    positive_int("hidden", r.hidden, maximum=MAX_HIDDEN)
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
    number_in("lr_floor", r.lr_floor, 0.0, 1.0)
    number_in("ent_floor", r.ent_floor, 0.0, 1.0)
    number_in("clip_coef", r.clip_coef, 0.0, 10.0, low_open=True)
    number_in("ent_coef", r.ent_coef, 0.0, 1000.0)
    number_in("vf_coef", r.vf_coef, 0.0, 1000.0)
    number_in("max_grad_norm", r.max_grad_norm, 0.0, 1e9, low_open=True)
    number_in("aux_coef", r.aux_coef, 0.0, 1000.0)
    number_in("recon_coef", r.recon_coef, 0.0, 1000.0)
    number_in("rnd_coef", r.rnd_coef, 0.0, 1000.0)
    number_in("rnd_proportion", r.rnd_proportion, 0.0, 1.0, low_open=True)
    number_in("rnd_floor", r.rnd_floor, 0.0, 1.0)
    number_in("rnd_hold", r.rnd_hold, 0.0, 1.0, high_open=True)
    if type(r.rnd_pool) is not int or r.rnd_pool not in RND_POOLS:  # not a bool, nor 2.0 from a JSON file
        raise ValueError(
            f"invalid value {r.rnd_pool!r} for option `rnd_pool`: allowed {', '.join(map(str, RND_POOLS))} (the side "
            "of the square of pixels the novelty bonus averages into one)"
        )
    number_in("teacher_coef", r.teacher_coef, 0.0, 1000.0)
    number_in("teacher_fade", r.teacher_fade, 0.0, 1.0, low_open=True)
    if not isinstance(r.teacher, str):
        raise ValueError(f"invalid value {r.teacher!r} for option `teacher`: allowed a model file's path, or ''")
    policy_seed(r.seed)
    for name in ("anneal_lr", "norm_obs", "norm_reward", "invert_frames", "torch_compile", "rnd_own_value"):
        check_bool(name, getattr(r, name))
    if not isinstance(r.obs_type, str):
        raise ValueError(f"invalid value {r.obs_type!r} for option `obs_type`: allowed a string")
    if r.augment not in AUGMENTS:
        raise ValueError(f"invalid value {r.augment!r} for option `augment`: allowed {', '.join(map(repr, AUGMENTS))}")
    if r.network not in NETWORKS:
        raise ValueError(f"invalid value {r.network!r} for option `network`: allowed {', '.join(map(repr, NETWORKS))}")
    check_device(r.device)
    mlp = r.network == "mlp" or (r.network == "auto" and r.obs_type == "features")
    for name, what in (
        ("aux_coef", "the auxiliary features loss"),
        ("recon_coef", "the reconstruction loss"),
        ("rnd_coef", "the novelty bonus"),
    ):
        if getattr(r, name) > 0 and mlp:
            raise ValueError(
                f"invalid value {getattr(r, name)!r} for option `{name}`: {what} is for CNN recipes (pixel "
                "observations); allowed 0 here"
            )
    for name, unset in (
        ("rnd_own_value", False),
        ("rnd_proportion", 1.0),
        ("rnd_pool", 1),
        ("rnd_floor", 1.0),
        ("rnd_hold", 0.0),
    ):
        if getattr(r, name) != unset and r.rnd_coef <= 0:
            raise ValueError(
                f"invalid value {getattr(r, name)!r} for option `{name}`: it is the novelty bonus's; allowed with "
                f"rnd_coef > 0 (else {unset})"
            )
    if r.rnd_hold > 0 and r.rnd_floor >= 1.0:
        raise ValueError(
            f"invalid value {r.rnd_hold!r} for option `rnd_hold`: it is where the novelty bonus's weight starts to "
            "fall; allowed with rnd_floor < 1 (else 0)"
        )
    if r.augment != "none" and mlp:
        raise ValueError(
            f"invalid value {r.augment!r} for option `augment`: augmentation is for CNN recipes (pixel observations); "
            "allowed 'none' here"
        )
    if r.network.endswith("-stem") and not r.invert_frames:
        raise ValueError(
            f"invalid value {r.network!r} for option `network`: its grey bands start at levels of inverted frames "
            "(the sky 0); allowed with invert_frames (drop --no-invert-frames), or another network"
        )
    if r.torch_compile and mlp:
        raise ValueError(
            "invalid value True for option `torch_compile`: compiling is for CNN recipes (pixel observations; the "
            "features MLP gains nothing from it); allowed False here"
        )
    if r.torch_compile:
        check_compiler()
    if r.teacher and mlp:
        raise ValueError(
            f"invalid value {r.teacher!r} for option `teacher`: a features teacher guides CNN recipes (pixel "
            "observations); allowed '' here"
        )
    if not isinstance(r.env_options, dict):
        raise ValueError(f"invalid value {r.env_options!r} for option `env_options`: allowed a dict of env options")
    for name in r.env_options:
        if name in RESERVED_OPTIONS:
            raise ValueError(f"env option `{name}` is not taken: {RESERVED_OPTIONS[name]}")
        if name not in ENV_OPTIONS:
            raise ValueError(f"unknown env option `{name}`: allowed {', '.join(ENV_OPTIONS)}")


def check_compiler() -> None:
    """`ValueError` unless a C++ compiler for `torch.compile`'s CPU kernels is on PATH (`CXX`, else `g++`)."""
    import shutil

    cxx = os.environ.get("CXX") or "g++"
    if shutil.which(cxx) is None:
        raise ValueError(
            f"option `torch_compile` needs a C++ compiler for torch.compile's CPU kernels, and {cxx!r} "
            f"{'(from CXX) ' if os.environ.get('CXX') else ''}is not on PATH: install one (Debian: apt install g++) or "
            "set CXX, or train without it (--no-torch-compile: the same settings otherwise, slower)"
        )


def check_minutes(minutes: float | None) -> None:
    """`ValueError` unless `minutes` (the wall-clock stop) is None or positive and finite."""
    if minutes is not None:
        number_in("minutes", minutes, 0.0, 1e7, low_open=True)


def check_until(until: int | None) -> None:
    """`ValueError` unless `until` (the env-step stop) is None or a positive number of steps."""
    if until is not None:
        positive_int("until", until, maximum=MAX_TOTAL_STEPS)


def read_recipe(path: Path) -> Recipe:
    """The recipe a run's `recipe.json` holds, every setting checked (`ValueError` naming the file and what is
    wrong: not a file, not JSON, an unknown setting, a value out of range)."""
    from .._checks import regular_file

    regular_file(path, str(path), 1 << 20)
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ValueError(f"{path}: not a recipe ({e})") from None
    names = {f.name for f in fields(Recipe)}
    if not isinstance(data, dict) or set(data) - names:
        unknown = sorted(set(data) - names) if isinstance(data, dict) else []
        raise ValueError(f"{path}: not a recipe of this trainer (unknown settings {unknown})")
    try:
        recipe = Recipe(**data)
    except TypeError as e:
        raise ValueError(f"{path}: not a recipe of this trainer ({e})") from None
    check_recipe(recipe)
    return recipe


def network_of(recipe: dict[str, Any] | Recipe) -> str:
    """The network a recipe trains: its `network`, with "auto" resolved by its obs_type."""
    r = recipe if isinstance(recipe, dict) else asdict(recipe)
    net = r.get("network", "mlp")
    if net == "auto":
        return "mlp" if r["obs_type"] == "features" else "small"
    return net
