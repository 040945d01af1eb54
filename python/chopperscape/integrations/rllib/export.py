"""A trained RLlib PPO as a ChopperScape policy file (ONNX, the format of `python -m chopperscape.learn.export`), with
the runners' observation filter frozen into the graph. Re-exported by :mod:`chopperscape.integrations.rllib`."""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from ray.rllib.utils.filter import SMALL_NUMBER

from . import VECTOR_ONLY


def observation_filter_state(env_runner: Any) -> dict:
    """The MeanStdFilter connector's state on a runner (runs in the runner); {} without one."""
    from ray.rllib.connectors.env_to_module.mean_std_filter import MeanStdFilter

    for connector in env_runner._env_to_module.connectors:
        if isinstance(connector, MeanStdFilter):
            return connector.get_state()
    return {}


def observation_filter(algo: Any, space: gym.spaces.Space) -> Any:
    """The observation filter of `algo`'s runners (RLlib's `MeanStdFilter` connector, synced across them) as a
    `ray.rllib.utils.filter.MeanStdFilter` over `space`, to apply with `update=False`; `None` when the runners
    have none (pixels). `ValueError` when the runners cannot be reached."""
    from ray.rllib.connectors.env_to_module.mean_std_filter import MeanStdFilter

    states = algo.env_runner_group.foreach_env_runner(observation_filter_state, local_env_runner=True)
    states = [s for s in states if s]
    if not states:
        return None
    connector = MeanStdFilter()  # (given the space in its constructor, it reads its clip before setting it)
    connector.input_observation_space = space
    connector.set_state(states[0])
    return connector._filters[None]


def export_onnx(
    algo: Any,
    env_config: Mapping[str, Any],
    out: str | os.PathLike[str],
    *,
    train_seeds: list[tuple[int, int]],
    source_sha256: str,
    force: bool = False,
) -> dict[str, Any]:
    """Writes the greedy policy of a trained PPO `algo` to `out` as a ChopperScape policy file, the format of
    `python -m chopperscape.learn.export` (read by `python -m chopperscape.bench evaluate`, the command line, the
    Rust crate and the page): the env's raw observation batch to the logits of the five actions, with what the
    runners apply first in the graph (the observation filter's frozen mean and std for features; the [0, 1]
    scaling for pixels). `train_seeds`: the reset-seed ranges `(first, count)` the runners trained on (written to
    the file, checked by the bench); `source_sha256`: the digest of the weights. The export's logits are compared
    with the module's on 1,000 observations recorded by playing it (`RuntimeError` beyond the tolerance); the file
    is written whole or not at all. Returns what was written and checked. `ValueError` for a bad `out`."""
    import torch

    from ... import FEATURES_VERSION, PIXELS_VERSION, policyfile
    from ...modes import with_mode
    from ...policyfile import observation_shape

    out = Path(out)
    policyfile.check_out(out, force)
    config = dict(env_config)
    obs_type = config.pop("obs_type", "features")
    name = config.pop("mode", None)
    options = {k: v for k, v in config.items() if k not in ("max_episode_steps", *VECTOR_ONLY)}
    if name is not None:
        options = with_mode(name, options)
    shape = observation_shape({"obs_type": obs_type, **options})
    space = gym.spaces.Box(-np.inf, np.inf, shape, np.float32)
    norm = observation_filter(algo, space) if obs_type == "features" else None
    if obs_type == "features" and norm is None:
        raise ValueError("no runner has the observation filter's statistics to export with")
    module = algo.get_module()

    class Policy(torch.nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.module = module
            if norm is not None:
                stats = norm.running_stats
                mean = np.asarray(stats.mean) if norm.demean else np.zeros(shape)
                scale = 1.0 / (np.asarray(stats.std) + SMALL_NUMBER) if norm.destd else np.ones(shape)
                self.register_buffer("mean", torch.as_tensor(mean, dtype=torch.float32))
                self.register_buffer("scale", torch.as_tensor(scale, dtype=torch.float32))
                self.clip = float(norm.clip) if norm.clip else None

        def forward(self, obs: torch.Tensor) -> torch.Tensor:
            if norm is not None:
                x = (obs - self.get_buffer("mean")) * self.get_buffer("scale")
                x = torch.clamp(x, -self.clip, self.clip) if self.clip is not None else x
            else:  # as FloatPixels: [0, 1], a channel axis for a plain grayscale frame
                x = obs.float() / 255.0 if obs.dtype == torch.uint8 else obs.float()
                x = x.unsqueeze(-1) if len(shape) == 2 else x
            return self.module.forward_inference({"obs": x})["action_dist_inputs"]

    policy = Policy().eval()
    dtype = torch.uint8 if obs_type in ("rgb", "grayscale") else torch.float32
    props = policyfile.metadata(
        obs_type,
        shape,
        options,
        source_sha256=source_sha256,
        features_version=FEATURES_VERSION,
        pixels_version=PIXELS_VERSION,
        train_seeds=train_seeds,
    )

    def logits(obs: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            return policy(torch.from_numpy(obs)).numpy()

    data = policyfile.to_onnx(policy, torch.zeros((2, *shape), dtype=dtype), props)
    result: dict[str, Any] = {"out": str(out), "obs_type": obs_type, "obs_shape": list(shape), "bytes": len(data)}
    result.update(policyfile.check_logits(data, logits, obs_type, options))
    policyfile.write(out, data)
    return result
