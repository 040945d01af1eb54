"""Evaluates any policy under the protocol on one mode and writes a results file.

    python -m chopperscape.bench evaluate POLICY --mode MODE [--policy-seed R] [--out FILE]

`POLICY` is one of:

- a built-in policy's name (`random`, `heuristic`, `noop`, …; a file of that name is given as `./NAME`);
- a `chopperscape.learn.train` model (`.pt`, read with `torch.load(weights_only=True)`);
- an exported policy (`.onnx`, from `python -m chopperscape.learn.export`; run by onnxruntime);
- a Stable-Baselines3 PPO or DQN `.zip` (give the observation it was trained on: `--option obs_type=features`);
- a Python callable by import path, `pkg.mod:func`, called as `func(obs_batch) -> actions` on a batch of
  observations (`--option` chooses them; features by default); or, when it has a `seed` parameter, a *policy
  factory* called once per run as `func(seed=R, stochastic=..., **args) -> policy`: `R` is `--policy-seed`,
  `stochastic` is `--stochastic` (refused for a callable without that parameter), and `args` are the
  `--policy-arg KEY=VALUE` strings (recorded as `policy.args`). Its module may declare the files it reads,
  `FILES = ["{weights}", ...]` (each formatted with the policy arguments): they are hashed with its source
  (`policy.files`, and `policy.sha256` over them all).

The mode fixes the rules (a model's own training rules are replaced by the mode's); `--option NAME=VALUE` takes
observation options only. The run is the protocol's (:mod:`.protocol`): 100 episodes from seed 1,000,000, the
10,000-step limit, greedy actions for trained policies (`--stochastic` samples, seeded by `--policy-seed`). The
results file (:mod:`.results`) is written atomically to `--out` (otherwise printed); an `--out` that is the policy
file, a folder, a device or a pipe is refused before anything is played. A model plays the observation it learned
(an ONNX export its pixel layout, `look`, as its `.pt` does), and the results file records it. Exit status 0; 2
with one line on standard error for a bad argument, a policy that cannot be read or returns no actions, or a
policy trained on the evaluation seeds; 130 on Ctrl-C.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import inspect
import json
import platform
import random
import sys
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .. import PIXELS_VERSION, __version__, _atomic, _core, modes
from ..options import OBSERVATION_OPTIONS, PYTHON_BOOL_OPTIONS
from ..policies import NAMES, VectorPolicy
from ..policyfile import TRAIN_SEEDS
from ..vector import VectorEnv
from . import protocol, record, results

#: What `--option` takes: observation options only (a mode fixes the rules; the protocol the step limit): the
#: core's observation settings (`look` included) and the Python environments' `keep_dim`.
OBS_OPTIONS = (*OBSERVATION_OPTIONS, *PYTHON_BOOL_OPTIONS)

Act = Callable[[np.ndarray, VectorEnv], np.ndarray]


class Builtin:
    """A built-in policy over each chunk of episodes: episode `k`'s policy seeded `run · 2**32 + k`."""

    def __init__(self, name: str, run: int):
        self.name, self.run = name, run
        self.policy: VectorPolicy | None = None

    def start_chunk(self, n: int, seed: int) -> None:
        self.policy = VectorPolicy(self.name, n, seed=protocol.policy_seed(self.run, seed - protocol.EVAL_SEED))

    def __call__(self, obs: np.ndarray, envs: VectorEnv) -> np.ndarray:
        assert self.policy is not None
        return self.policy.act(envs)


class Loaded:
    """A policy ready to play: how it acts, the env options it plays with, and what the results file says of it."""

    def __init__(self, act: Act, options: dict[str, Any], info: dict[str, Any]):
        self.act, self.options, self.info = act, options, info


def _need(module: str, what: str) -> None:
    if importlib.util.find_spec(module) is None:
        raise ValueError(f"{what} needs {module}, which is not installed: pip install {module.replace('_', '-')}")


def load(
    policy: str,
    mode: str,
    options: dict[str, Any] | None = None,
    stochastic: bool = False,
    run: int = 0,
    trust_pickle: bool = False,
    args: dict[str, str] | None = None,
) -> Loaded:
    """The policy `policy` (see the module's docs) set up to play mode `mode` with observation `options`."""
    options = dict(options or {})
    bad = sorted(set(options) - set(OBS_OPTIONS))
    if bad:
        raise ValueError(f"option {bad[0]!r}: the bench takes observation options only ({', '.join(OBS_OPTIONS)})")
    rules = protocol.mode_options(mode)
    actions = "sampled" if stochastic else "greedy"
    info: dict[str, Any] = {"source": policy, "sha256": None, "recipe": None, "train_seeds": None}
    is_callable = policy not in NAMES and ":" in policy and not Path(policy).exists()
    if args and not is_callable:
        raise ValueError(f"--policy-arg is for a callable policy pkg.mod:func; {policy!r} is not one")
    if policy in NAMES:
        if stochastic:
            raise ValueError(f"--stochastic is for trained policies; built-in {policy!r} acts as it is")
        info.update(kind="builtin", actions="as-is")
        return Loaded(Builtin(policy, run), {"obs_type": "features", **options, **rules}, info)
    if is_callable:
        return _callable(
            policy, {**options, **rules}, stochastic, run, results.check_policy_args(dict(args or {})), info
        )
    path = Path(policy)
    if not path.is_file():
        raise ValueError(
            f"policy {policy!r} is not a file, a built-in policy ({', '.join(NAMES)}) or an import path pkg.mod:func"
        )
    info["sha256"] = _atomic.sha256(path)
    info["actions"] = actions
    if path.suffix == ".onnx":
        return _onnx(path, options, rules, stochastic, run, info)
    _need("torch", f"policy file {policy!r}")
    from ..learn import players

    if path.suffix == ".zip":
        _need("stable_baselines3", f"policy file {policy!r}")
        import torch

        torch.manual_seed(run)
        from ..integrations.sb3_files import algorithm

        algo = algorithm(path)
        act, played = players.load_sb3(path, stochastic, {**options, **rules}, trust_pickle, algo)
        info.update(kind="sb3", recipe={"algorithm": algo})
        return Loaded(act, played, info)
    from ..learn.modelfile import load as load_model

    recipe = load_model(path).recipe
    info.update(kind="recipe", recipe=recipe)
    seed, num_envs = recipe.get("seed"), recipe.get("num_envs")
    if isinstance(seed, int) and isinstance(num_envs, int):
        protocol.check_training_seeds(seed, num_envs, f"policy file {policy!r}: its training")
        info["train_seeds"] = [seed, num_envs]
    act, played = players.load_recipe(path, stochastic, run, {**options, **rules})
    return Loaded(act, played, info)


def _onnx(path: Path, options: dict, rules: dict, stochastic: bool, run: int, info: dict) -> Loaded:
    _need("onnxruntime", f"policy file {str(path)!r}")
    import onnxruntime as ort

    try:
        session = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    except Exception as e:  # onnxruntime raises its own exception types
        raise ValueError(f"policy file {str(path)!r} is not a readable ONNX model ({str(e).splitlines()[0]})") from None
    meta = dict(session.get_modelmeta().custom_metadata_map)
    if not meta.get("format", "").startswith("chopperscape-policy/"):
        raise ValueError(
            f"policy file {str(path)!r} has no chopperscape-policy metadata (export it with "
            "python -m chopperscape.learn.export)"
        )
    try:
        trained = json.loads(meta.get("env_options", "{}"))
    except (ValueError, RecursionError):
        trained = None
    if not isinstance(trained, dict):
        raise ValueError(
            f"policy file {str(path)!r}: its env_options metadata must be a JSON object of options, e.g. "
            '{"frame_skip": 4}'
        )
    ranges = _train_seeds(meta.get(TRAIN_SEEDS), path)
    for first, count in ranges:
        protocol.check_training_seeds(first, count, f"policy file {str(path)!r}: its training")
    if len(ranges) == 1:  # several ranges (one per RLlib runner) stay in the recorded metadata only
        info["train_seeds"] = list(ranges[0])
    # The observation it was trained on, its pixel layout included: an older layout (`pixels_version`) is drawn
    # under the options `_core.PIXEL_LAYOUTS` names (`look="art"` for layout 2), as the `.pt` it was exported
    # from plays (`learn.modelfile.learned_options`); its env_options' own `look` where it has one. `--option` may
    # change them (and the model's input is then checked against the observation they give).
    obs_type = meta.get("obs_type", "features")
    layout: dict[str, Any] = {}
    if obs_type != "features":
        version = meta.get("pixels_version", str(PIXELS_VERSION))
        if version != str(PIXELS_VERSION) and not (version.isdigit() and int(version) in _core.PIXEL_LAYOUTS):
            raise ValueError(
                f"policy file {str(path)!r}: it learned pixel layout {version[:20]!r}, and this chopperscape draws "
                f"{PIXELS_VERSION} (and the older {', '.join(map(str, sorted(_core.PIXEL_LAYOUTS)))})"
            )
        layout = dict(_core.PIXEL_LAYOUTS.get(int(version), {}))
    obs = {k: v for k, v in trained.items() if k in OBS_OPTIONS}
    obs = {"obs_type": obs_type, **layout, **obs, **options}
    if "obs_size" in obs and isinstance(obs["obs_size"], list):
        obs["obs_size"] = tuple(obs["obs_size"])
    info.update(kind="onnx", recipe=meta)
    inputs, outputs = session.get_inputs(), session.get_outputs()
    if len(inputs) != 1 or len(outputs) < 1:
        raise ValueError(
            f"policy file {str(path)!r} has {len(inputs)} inputs and {len(outputs)} outputs: a policy has one input "
            "(a batch of observations) and its first output is the logits"
        )
    from ..policyfile import observation_shape

    try:
        shape = observation_shape({**obs, **rules})
    except ValueError as e:
        raise ValueError(f"policy file {str(path)!r}: its observation options cannot be played ({e})") from None
    declared = list(inputs[0].shape or [])[1:]
    if len(declared) != len(shape) or any(isinstance(d, int) and d != s for d, s in zip(declared, shape)):
        raise ValueError(
            f"policy file {str(path)!r} takes observations of shape {tuple(declared)}, but its options give "
            f"{shape} ({', '.join(f'{k}={v!r}' for k, v in obs.items())}): give the options it was trained with"
        )
    name = inputs[0].name
    gen = np.random.default_rng(run)

    def act(batch: np.ndarray, envs: VectorEnv) -> np.ndarray:
        try:
            logits = np.asarray(session.run(None, {name: batch})[0])
        except Exception as e:  # onnxruntime's own exception types
            raise ValueError(f"policy file {str(path)!r} cannot be run ({str(e).splitlines()[0][:200]})") from None
        if logits.ndim != 2 or logits.shape[0] != len(batch) or logits.shape[1] < 1:
            raise ValueError(
                f"policy file {str(path)!r} gives outputs of shape {logits.shape} for {len(batch)} observations: a "
                "policy gives a row of logits per observation"
            )
        if not stochastic:
            return logits.argmax(-1)
        p = np.exp(logits - logits.max(-1, keepdims=True))
        p /= p.sum(-1, keepdims=True)
        return (p.cumsum(-1) > gen.random((len(p), 1))).argmax(-1)

    return Loaded(act, {**obs, **rules}, info)


def _train_seeds(text: str | None, path: Path) -> list[tuple[int, int]]:
    """The `train_seeds` metadata of an exported policy, `[[first, count], ...]` (none when absent)."""
    if text is None:
        return []
    try:
        value = json.loads(text)
    except ValueError:
        value = None

    def whole(x: Any) -> bool:
        return isinstance(x, int) and not isinstance(x, bool)

    if not isinstance(value, list) or not all(
        isinstance(pair, list) and len(pair) == 2 and all(whole(x) for x in pair) for pair in value
    ):
        raise ValueError(
            f"policy file {str(path)!r}: its train_seeds metadata must be JSON [[first, count], ...], got {text[:80]!r}"
        )
    return [(first, count) for first, count in value]


def _declared_files(spec: str, module: Any, args: dict[str, str]) -> list[str]:
    """The files a callable's module declares it reads (`FILES`, each entry formatted with the policy arguments)."""
    declared = getattr(module, "FILES", ())
    if isinstance(declared, str) or not (
        isinstance(declared, (list, tuple)) and all(isinstance(f, str) and f for f in declared)
    ):
        raise ValueError(f"policy {spec!r}: its module's FILES must be a list of paths, e.g. ['{{weights}}']")
    out = []
    for entry in declared:
        try:
            path = entry.format(**args)
        except (KeyError, IndexError, ValueError) as e:
            raise ValueError(
                f"policy {spec!r}: its FILES entry {entry!r} names a policy argument not given ({e}): give it with "
                "--policy-arg KEY=VALUE"
            ) from None
        from .._checks import regular_file

        regular_file(path, f"policy {spec!r}: its declared file {path!r}")
        out.append(path)
    return out


def _callable(spec: str, options: dict, stochastic: bool, run: int, args: dict[str, str], info: dict) -> Loaded:
    """A policy by import path. `func(obs_batch) -> actions` is called on each batch as it is; a *policy factory*,
    a callable with a `seed` parameter, is called once, `func(seed=RUN, [stochastic=...], **args)`, and returns the
    batch policy. The files its module's `FILES` declares (formatted with `args`) are hashed with its source."""
    mod_name, _, attr = spec.partition(":")
    try:
        module = importlib.import_module(mod_name)
        func = module
        for part in attr.split("."):
            func = getattr(func, part)
    except (ImportError, AttributeError, TypeError, ValueError) as e:  # TypeError, ValueError: "..", "", "a..b"
        raise ValueError(f"policy {spec!r}: cannot import it ({e}); give pkg.mod:func") from None
    if not callable(func):
        raise ValueError(f"policy {spec!r} is not callable")
    try:
        params = inspect.signature(func).parameters
    except (TypeError, ValueError):  # some built-ins have no signature
        params = {}  # type: ignore[assignment]
    kwargs = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values())
    factory = "seed" in params
    takes_stochastic = factory and ("stochastic" in params or kwargs)
    if not factory and args:
        raise ValueError(
            f"--policy-arg: policy {spec!r} is called as func(obs_batch) and takes no arguments; a policy factory "
            "func(*, seed, stochastic=False, **args) -> policy does (docs/site/bench.md)"
        )
    if stochastic and not takes_stochastic:
        raise ValueError(
            f"--stochastic: policy {spec!r} cannot be asked to sample its actions (it has no `stochastic` parameter): "
            "evaluate it as it acts, or give it one (a policy factory, docs/site/bench.md)"
        )
    unknown = sorted(k for k in args if k not in params and not kwargs)
    if factory and unknown:
        allowed = [k for k in params if k not in ("seed", "stochastic")]
        raise ValueError(
            f"--policy-arg {unknown[0]}: policy {spec!r} takes no such argument "
            f"(it takes {', '.join(allowed) or 'none'})"
        )
    files = _declared_files(spec, module, args)
    try:
        source = inspect.getsourcefile(module)
    except TypeError:  # a built-in module (builtins:len) has no source file
        source = None
    hashed = [[str(source), _atomic.sha256(Path(source))]] if source else []
    hashed += [[f, _atomic.sha256(f)] for f in files]
    sha = hashed[0][1] if len(hashed) == 1 and not files else None
    if files:
        sha = hashlib.sha256("".join(h for _, h in hashed).encode()).hexdigest()
    actions = "sampled" if stochastic else ("greedy" if takes_stochastic else "as-is")
    info.update(kind="callable", actions=actions, sha256=sha)
    if args:
        info["args"] = dict(args)
    if files:
        info["files"] = hashed
    # A callable drawing from Python's, numpy's or torch's global generator draws from one seeded by the run.
    random.seed(run)
    np.random.seed(run)
    if "torch" in sys.modules:
        sys.modules["torch"].manual_seed(run)
    batch_policy: Any = func
    if factory:
        try:
            batch_policy = func(seed=run, **({"stochastic": stochastic} if takes_stochastic else {}), **args)
        except Exception as e:  # the factory's own failure: said in one line, naming it
            raise ValueError(f"policy {spec!r} failed to start ({type(e).__name__}: {str(e)[:200]})") from None
        if not callable(batch_policy):
            raise ValueError(
                f"policy {spec!r} returned {type(batch_policy).__name__}: a policy factory returns a policy"
            )

    def act(batch: np.ndarray, envs: VectorEnv) -> np.ndarray:
        try:
            out = batch_policy(batch)
            actions = np.asarray(out)
        except Exception as e:  # the callable's own failure: said in one line, naming it
            raise ValueError(f"policy {spec!r} failed on a batch of observations ({type(e).__name__}: {e})") from None
        numeric = np.issubdtype(actions.dtype, np.integer) or np.issubdtype(actions.dtype, np.floating)
        if actions.shape != (len(batch),) or not numeric or not np.array_equal(actions, np.round(actions)):
            raise ValueError(
                f"policy {spec!r} returned {type(out).__name__} {str(out)[:60]!r}: a policy returns one action per "
                f"observation, an array of {len(batch)} integers in 0..=4"
            )
        return actions

    return Loaded(act, {"obs_type": "features", **options}, info)


def _observation(options: dict[str, Any]) -> dict[str, Any]:
    """What a results file records of the observation played: its observation options, and for frames the pixel
    layout (`look`) whether given or the default, so that two files of one model say whether they saw alike."""
    obs = {k: list(v) if isinstance(v, tuple) else v for k, v in options.items() if k in OBS_OPTIONS}
    if obs.get("obs_type", "features") != "features" and "look" not in obs:
        obs["look"] = next(o["default"] for o in _core.OPTIONS if o["name"] == "look")
    return obs


def run(
    policy: str,
    mode: str,
    options: dict[str, Any] | None = None,
    stochastic: bool = False,
    policy_seed: int = 0,
    trust_pickle: bool = False,
    train_seeds: tuple[int, int] | None = None,
    name: str | None = None,
    training: dict[str, Any] | None = None,
    command: list[str] | None = None,
    policy_args: dict[str, str] | None = None,
) -> dict[str, Any]:
    """Evaluates `policy` on mode `mode` under the protocol; the results document (checked). `train_seeds`
    (`(first, count)`) declares the reset seeds a policy was trained on where its file does not record them (an SB3
    `.zip`, a callable): they are checked against the evaluation seeds and recorded. `name` is the leaderboard row
    the run belongs to (`results.check_name`): the runs of one recipe's training seeds share it. `training` is a
    trained row's training record (:mod:`.record`; its one range of seeds stands for `train_seeds`), `command` the
    command line recorded as `meta.command`, `policy_args` a callable's `--policy-arg`s."""
    from ..learn.episodes import play_episodes

    if isinstance(policy_seed, bool) or not isinstance(policy_seed, int) or not 0 <= policy_seed < 2**31:
        raise ValueError(f"--policy-seed {policy_seed!r}: allowed 0 <= seed < 2**31")
    m = modes.mode(mode)
    if name is not None:
        results.check_name(name)
    if training is not None:
        record.check_training(training, m["name"])
        ranges = [tuple(r) for r in training["train_seeds"]]
        if train_seeds is not None and [tuple(train_seeds)] != ranges:
            raise ValueError(f"--train-seeds {train_seeds[0]}:{train_seeds[1]}: the training record says {ranges}")
        if train_seeds is None and len(ranges) == 1:
            train_seeds = (int(ranges[0][0]), int(ranges[0][1]))
    if train_seeds is not None:
        protocol.check_training_seeds(*train_seeds, what=f"policy {policy!r}: its declared training")
    loaded = load(policy, mode, options, stochastic, policy_seed, trust_pickle, policy_args)
    if train_seeds is not None:
        known = loaded.info["train_seeds"]
        if known is not None and known != list(train_seeds):
            raise ValueError(f"--train-seeds {train_seeds[0]}:{train_seeds[1]}: policy {policy!r} records {known}")
        loaded.info["train_seeds"] = list(train_seeds)
    episodes = play_episodes(
        loaded.act,
        protocol.EVAL_EPISODES,
        protocol.EVAL_SEED,
        loaded.options,
        max_episode_steps=protocol.MAX_EPISODE_STEPS,
    )
    doc = {
        "format": results.FORMAT,
        "mode": {"name": m["name"], "id": m["id"], "options": m["options"]},
        "protocol": protocol.PROTOCOL,
        "policy": {
            **loaded.info,
            **({} if name is None else {"name": name}),
            "policy_seed": policy_seed,
            "observation": _observation(loaded.options),
        },
        "package": {"name": "chopperscape", "version": __version__},
        "episodes": [{k: e[k] for k in ("seed", "return", "steps", "cause")} for e in episodes],
        "summary": results.summary(episodes, mode),
        "meta": {
            "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "python": platform.python_version(),
            "platform": sys.platform,
            **record.commit(),
            **({} if command is None else {"command": list(command)}),
        },
    }
    if training is not None:
        doc["training"] = training
    return results.check(json.loads(results.dumps(doc)))
