"""The policy file: an ONNX graph from a raw observation batch to the logits of the five actions, with
`metadata_props` that say what it takes (format ``chopperscape-policy/1``; the keys, the checks and the command
that writes one from a recipe model: :mod:`chopperscape.learn.export`). Every writer of such a file builds it here
(the recipe's export, the RLlib integration) and every reader checks these keys (the benchmark, the Rust crate
`chopperscape-policy`, the page). Also the observation shape a policy takes for a set of env options.

The format functions need torch and onnx (and onnxruntime for the logits check) when called; importing this
module needs neither.
"""

from __future__ import annotations

import io
import json
import os
import warnings
from pathlib import Path
from typing import Any, Callable

import gymnasium as gym
import numpy as np

from . import _atomic
from .vector import VectorEnv

#: The format written into `metadata_props["format"]` (the Rust crate reads this one).
FORMAT = "chopperscape-policy/1"
#: Observations the check compares logits on, and the largest difference allowed.
CHECK_OBSERVATIONS = 1000
CHECK_TOLERANCE = 1e-5
#: ONNX operator set of the export: within what tract is tested against (9 to 18).
OPSET = 17
#: The optional `metadata_props` key of the reset-seed ranges a policy was trained on, JSON `[[first, count], ...]`:
#: `python -m chopperscape.bench evaluate` refuses a policy whose ranges reach the evaluation seeds.
TRAIN_SEEDS = "train_seeds"


def record_observations(
    logits: Callable[[np.ndarray], np.ndarray],
    obs_type: str,
    options: dict[str, Any],
    n: int = CHECK_OBSERVATIONS,
    seed: int = 0,
) -> np.ndarray:
    """`n` raw observations met by playing the env greedily by `logits` (a raw observation batch to the actions'
    logits), 8 envs from seeds `seed + i`, autoreset."""
    envs = VectorEnv(8, num_threads=1, obs_type=obs_type, **options)
    try:
        obs, _ = envs.reset(seed=seed)
        seen = [obs.copy()]
        while sum(len(o) for o in seen) < n:
            obs, *_ = envs.step(np.asarray(logits(obs)).argmax(-1).astype(np.int64))
            seen.append(obs.copy())
    finally:
        envs.close()
    return np.concatenate(seen)[:n]


def check_out(out: Path, force: bool) -> None:
    """`ValueError` naming `--out` when the ONNX file cannot go there: its folder is missing or a file, it is a
    folder, or it exists and `force` is not given."""
    out_dir = out.parent if str(out.parent) else Path(".")
    if not out_dir.is_dir():
        why = "is not a folder" if os.path.lexists(out_dir) else "does not exist"
        raise ValueError(f"--out {str(out)!r}: {str(out_dir)!r} {why}")
    if out.is_dir():
        raise ValueError(f"--out {str(out)!r} is a folder: give the ONNX file to write (NAME.onnx)")
    if os.path.lexists(out) and not force:
        raise ValueError(f"--out {str(out)!r} exists: pass --force to replace it")


def metadata(
    obs_type: str,
    env_shape: tuple[int, ...],
    options: dict[str, Any],
    *,
    source_sha256: str,
    features_version: int,
    pixels_version: int,
    train_seeds: list[tuple[int, int]] | None = None,
) -> dict[str, str]:
    """The `metadata_props` of an exported policy (the module's docs; `crates/policy/src/metadata.rs` reads
    them). `train_seeds`: the reset-seed ranges `(first, count)` it was trained on, when known."""
    props = {
        "format": FORMAT,
        "obs_type": obs_type,
        "obs_shape": json.dumps(list(env_shape)),
        "env_options": json.dumps(options, sort_keys=True),
        "features_version": str(features_version),
        "pixels_version": str(pixels_version),
        "source_sha256": source_sha256,
    }
    if train_seeds is not None:
        props[TRAIN_SEEDS] = json.dumps([[int(first), int(count)] for first, count in train_seeds])
    return props


def to_onnx(module, example, props: dict[str, str]) -> bytes:
    """`module` (raw observation batch to logits) as a checked ONNX graph, traced on `example`: input `obs`,
    output `logits`, the batch axis free, `props` as its `metadata_props`."""
    import onnx
    import torch

    # The TorchScript exporter: the graph of these small static networks needs nothing of torch.export's
    # (control flow, dynamic shapes), and it needs no onnxscript. torch 2.9+ warns that it is the legacy one.
    # Built in memory and checked there; the caller writes it once, whole (`_atomic`), or not at all.
    buffer = io.BytesIO()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        torch.onnx.export(
            module,
            (example,),
            buffer,  # type: ignore[arg-type]  # file objects are taken (torch.onnx.export docs: `f`)
            input_names=["obs"],
            output_names=["logits"],
            dynamic_axes={"obs": {0: "batch"}, "logits": {0: "batch"}},
            opset_version=OPSET,
            dynamo=False,
        )
    graph = onnx.load_from_string(buffer.getvalue())
    del graph.metadata_props[:]
    for key, value in props.items():
        graph.metadata_props.add(key=key, value=value)
    graph.producer_name = "chopperscape.learn.export"
    onnx.checker.check_model(graph)
    return graph.SerializeToString()


def check_logits(
    onnx_model: bytes, logits: Callable[[np.ndarray], np.ndarray], obs_type: str, options: dict[str, Any]
) -> dict[str, Any]:
    """Compares the export's logits with `logits` (the source policy's, raw observations in) on
    `CHECK_OBSERVATIONS` observations recorded by playing it; `RuntimeError` when they differ by more than
    `CHECK_TOLERANCE`. Skipped (and said so) without onnxruntime, before anything is played."""
    try:
        import onnxruntime
    except ImportError:
        return {"checked": False, "why": "onnxruntime is not installed (pip install onnxruntime)"}
    obs = record_observations(logits, obs_type, options)
    session = onnxruntime.InferenceSession(onnx_model, providers=["CPUExecutionProvider"])
    got = session.run(["logits"], {"obs": obs})[0]
    diff = float(np.max(np.abs(got - logits(obs))))
    if not diff <= CHECK_TOLERANCE:
        raise RuntimeError(f"the export's logits differ from torch's by {diff:.3g} (allowed {CHECK_TOLERANCE})")
    return {"checked": True, "observations": len(obs), "max_abs_diff": diff}


def write(out: Path, data: bytes) -> None:
    """Writes the export `data` to `out` whole or not at all; `ExportWriteError` naming `out` otherwise."""
    try:
        _atomic.write_bytes(out, data)
    except OSError as e:
        raise ExportWriteError(f"cannot write {str(out)!r}: {e.strerror or e}; nothing was written") from None


class ExportWriteError(OSError):
    """The export could not be written (a read-only folder, a full disk): the message names `--out`."""


def observation_space(options: dict[str, Any]) -> gym.Space:
    """The observation space of one env with `options` (a `ValueError` naming a bad option)."""
    options = {"max_episode_steps": None, **options}
    envs = VectorEnv(1, num_threads=1, **options)
    try:
        return envs.single_observation_space
    finally:
        envs.close()


def observation_shape(options: dict[str, Any]) -> tuple[int, ...]:
    """The observation shape of one env with `options` (a `ValueError` naming a bad option)."""
    return tuple(observation_space(options).shape or ())


def seed_ranges(seeds: list[int | None]) -> list[tuple[int, int]]:
    """Reset seeds as the sorted ranges `(first, count)` of consecutive seeds that a policy file's `train_seeds`
    holds; `ValueError` if an env was reset without a seed (its games are then unknown)."""
    if any(s is None for s in seeds):
        raise ValueError("an env was reset without a seed: its training seeds are unknown (give the run a --seed)")
    ranges: list[list[int]] = []
    for s in sorted({int(s) for s in seeds if s is not None}):
        if ranges and ranges[-1][0] + ranges[-1][1] == s:
            ranges[-1][1] += 1
        else:
            ranges.append([s, 1])
    return [(first, count) for first, count in ranges]
