"""Exports a trained policy to ONNX, for the `chopperscape` command line, the Rust crate `chopperscape-policy`
and any ONNX runtime.

    python -m chopperscape.learn.export runs/ppo/model.pt --out ppo.onnx

`MODEL` is a file written by ``python -m chopperscape.learn.train`` (``model.pt``, features MLP or pixel CNN), read with
``torch.load(weights_only=True)``: a file that holds anything but tensors and plain data is refused, so exporting
never runs code from it.

The exported graph maps a batch of raw observations, exactly as the env gives them (``float32`` features,
``uint8`` frames ``(N, H, W)`` or ``(N, H, W, k)``), to the logits of the five actions: the observation
normalisation the model was trained with (mean and variance, ε = 1e-8, clipped to ±10, as ``train.ObsNormalizer``)
is part of the graph. Its input is ``obs`` (batch axis ``batch``) and its output ``logits``. The greedy action is
the argmax of the logits.

The file's ``metadata_props`` say what the policy takes (the Rust loader refuses a file without them):

    format            chopperscape-policy/1
    obs_type          features | grayscale | rgb | rgb_float
    obs_shape         one observation's shape, JSON ([46], [84, 84, 4])
    env_options       the env options it was trained with, JSON ({"frame_skip": 4, "obs_size": [84, 84], ...})
    features_version  the features layout it learned (chopperscape.FEATURES_VERSION)
    pixels_version    the pixel layout it learned (chopperscape.PIXELS_VERSION)
    source_sha256     the SHA-256 of MODEL
    train_seeds       the reset seeds it was trained on, JSON ranges [[first, count], ...]: optional (files
                      exported by 0.1.0 lack it; `python/examples/rllib_ppo.py --export` writes one per runner)

The export is built and checked in memory before anything is written: its logits must equal torch's within 1e-5 on
1,000 observations recorded by playing the env with the policy (with ``onnxruntime`` when it is installed;
otherwise the check is skipped and says so: ``pip install onnxruntime``); then ``--out`` is written whole or not at
all (:mod:`chopperscape._atomic`). Exit status 0, or 2 with one line on standard error naming the input (a missing
file, a folder or a device, a file that is not a recipe model, an ``--out`` under a file or that is a folder, an
existing ``--out`` without ``--force``), 1 if the check fails or ``--out`` cannot be written (a read-only folder, a
full disk: nothing is left behind).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np

from .. import _atomic
from .._cli import print_line, run_command
from ..policyfile import (
    check_logits,
    check_out,
    metadata,
    observation_shape,
    to_onnx,
    write,
)


def load(path: Path):
    """`(payload, agent, norm, env_options, env_shape)` of a recipe model; `ValueError` with one line for a
    missing file, one that is not a recipe model, or one that holds more than tensors and plain data."""
    from .modelfile import from_payload, read_checkpoint

    what = f"model file {str(path)!r}"
    if not os.path.lexists(path):
        raise ValueError(f"{what} does not exist (give a model.pt from python -m chopperscape.learn.train)")
    payload = read_checkpoint(path, what)  # a regular file of a model's size, tensors and plain data
    agent, model_shape, norm, recipe = from_payload(payload, what)
    # The env's own observation (the Rust env has no `keep_dim`: a grayscale frame without a channel axis).
    # The options it was trained with, as written in the file: a policy of an older pixel layout says so by its
    # `pixels_version`, and every loader (the policy crate, `modelfile.learned_options`) draws it that layout.
    options = {k: v for k, v in payload["recipe"].get("env_options", {}).items() if k != "keep_dim"}
    env_shape = observation_shape({"obs_type": recipe["obs_type"], **options})
    if int(np.prod(env_shape)) != int(np.prod(model_shape)):
        raise ValueError(f"{what} takes observations of shape {model_shape}, but its env options give {env_shape}")
    return payload, agent, norm, options, env_shape


def _policy_module(agent, norm, model_shape: tuple[int, ...], env_shape: tuple[int, ...]):
    """The torch module that is exported: the env's raw observation batch to logits."""
    import torch
    from torch import nn

    class Policy(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.actor = agent.actor
            self.reshape = tuple(model_shape) != tuple(env_shape)
            self.normalise = norm.enabled
            if norm.enabled:
                std = np.sqrt(norm.rms.var + 1e-8)
                self.register_buffer("mean", torch.as_tensor(norm.rms.mean, dtype=torch.float32))
                self.register_buffer("inv_std", torch.as_tensor(1.0 / std, dtype=torch.float32))

        def forward(self, obs: torch.Tensor) -> torch.Tensor:
            x = obs.reshape(-1, *model_shape) if self.reshape else obs
            if self.normalise:
                mean, inv_std = self.get_buffer("mean"), self.get_buffer("inv_std")
                x = torch.clamp((x.float() - mean) * inv_std, -10.0, 10.0)
            return self.actor(x)

    return Policy().eval()


def payload_shape(payload: dict[str, Any]) -> tuple[int, ...]:
    """One observation's shape as the model takes it."""
    return tuple(payload.get("obs_shape") or (payload["obs_dim"],))


def export(model: Path, out: Path, force: bool = False, check: bool = True) -> dict[str, Any]:
    """Writes the ONNX export of `model` to `out` (atomically: a temporary file beside it, renamed), then checks
    it (see the module docs). Returns what the command line prints. `ValueError` for a bad model or `out`;
    `RuntimeError` when the check fails (the file is removed)."""
    import torch

    check_out(out, force)
    if os.path.lexists(out) and os.path.lexists(model) and os.path.samefile(out, model):
        raise ValueError(f"--out {str(out)!r} is the model file itself: give another name (NAME.onnx)")
    payload, agent, norm, options, env_shape = load(model)
    obs_type = payload["recipe"]["obs_type"]
    module = _policy_module(agent, norm, payload_shape(payload), env_shape)
    # The env's element type: uint8 frames (rgb, grayscale), float32 otherwise (features, rgb_float).
    dtype = torch.uint8 if obs_type in ("rgb", "grayscale") else torch.float32
    example = torch.zeros((2, *env_shape), dtype=dtype)
    pixels = obs_type != "features"
    from .. import FEATURES_VERSION, PIXELS_VERSION

    seed, num_envs = payload["recipe"].get("seed"), payload["recipe"].get("num_envs")
    props = metadata(
        obs_type,
        env_shape,
        options,
        source_sha256=_atomic.sha256(model),
        # A file without versions predates them: features v2, pixel layout 1.
        features_version=int(payload.get("features_version", 2 if not pixels else FEATURES_VERSION)),
        pixels_version=int(payload.get("pixels_version", 1 if pixels else PIXELS_VERSION)),
        train_seeds=[(seed, num_envs)] if isinstance(seed, int) and isinstance(num_envs, int) else None,
    )
    data = to_onnx(module, example, props)
    result: dict[str, Any] = {
        "model": str(model),
        "out": str(out),
        "obs_type": obs_type,
        "obs_shape": list(env_shape),
        "bytes": len(data),
    }
    if check:
        result.update(check_export(data, payload, agent, norm, options))
    write(out, data)
    return result


def check_export(onnx_model: bytes, payload: dict[str, Any], agent, norm, options: dict[str, Any]) -> dict[str, Any]:
    """:func:`check_logits` against the model's actor (its normaliser applied first)."""
    import torch

    def logits(obs: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            return agent.actor(torch.from_numpy(norm(obs).reshape(len(obs), *payload_shape(payload)))).numpy()

    return check_logits(onnx_model, logits, payload["recipe"]["obs_type"], options)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m chopperscape.learn.export", description=__doc__.splitlines()[0])
    p.add_argument("model", help="model.pt from python -m chopperscape.learn.train")
    p.add_argument("--out", required=True, help="the ONNX file to write (NAME.onnx)")
    p.add_argument("--force", action="store_true", help="replace --out if it exists")
    p.add_argument("--no-check", action="store_true", help="skip comparing the export's logits with torch's")
    a = p.parse_args(argv)
    return run_command(lambda: print_line(json.dumps(_export(a))))


def _export(a: argparse.Namespace) -> dict[str, Any]:
    """What `main` does with its flags `a`: the export's result line as a dict."""
    try:
        import onnx  # noqa: F401
        import torch

        torch.set_num_threads(1)
    except ImportError as err:
        raise ImportError(f"exporting needs torch and onnx: pip install torch onnx ({err})") from None
    return export(Path(a.model), Path(a.out), a.force, check=not a.no_check)


if __name__ == "__main__":
    sys.exit(main())
