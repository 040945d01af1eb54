"""ChopperScape-v0 for Gymnasium: a Rust game behind a `gymnasium.Env` and a native `gymnasium.vector.VectorEnv`.

Importing the package registers `ChopperScape-v0` and one id per difficulty mode of ChopperScape-Bench
(`MODES`: `ChopperScape-Sticky-v0`, `ChopperScape-Full-v0`; `mode="sticky-v0"` chooses the same rules):

>>> import gymnasium as gym, chopperscape
>>> env = gym.make("ChopperScape-v0", obs_type="features")
>>> envs = gym.make_vec("ChopperScape-v0", num_envs=8, vectorization_mode="vector_entry_point", obs_type="features")
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

from . import _core, policies
from .env import ChopperScapeEnv, clone_state, restore_state
from .modes import MODES
from .vector import VectorEnv

__all__ = [
    "ACTION_MEANINGS",
    "FEATURES_VERSION",
    "MODES",
    "NUM_ACTIONS",
    "OPTION_NAMES",
    "PIXELS_VERSION",
    "ChopperScapeEnv",
    "VectorEnv",
    "__version__",
    "clone_state",
    "policies",
    "restore_state",
]
__version__ = _core.__version__
ACTION_MEANINGS: list[str] = list(_core.ACTION_MEANINGS)
#: The size of the action space, `Discrete(NUM_ACTIONS)`: one action per meaning.
NUM_ACTIONS: int = len(_core.ACTION_MEANINGS)
OPTION_NAMES: list[str] = [n for n in _core.OPTION_NAMES if n != "max_episode_steps"] + ["render_mode"]
#: The layout version of the `"features"` observation.
FEATURES_VERSION: int = _core.FEATURES_VERSION
#: The version of what pixel observations show (docs/SPEC.md, "HUD and pixel layout"): 3 = the agent view in
#: frames under 300 × 400 with the default `look="auto"`; 2 = the art there, with the fuel and lives gauges
#: (`hud_style="auto"`); 1 = the text line at every size.
PIXELS_VERSION: int = _core.PIXELS_VERSION

if "ChopperScape-v0" not in registry:
    register(
        id="ChopperScape-v0",
        entry_point="chopperscape.env:registered",
        vector_entry_point="chopperscape.vector:VectorEnv",
        max_episode_steps=10_000,
    )
# One id per rung. ChopperScape-v0 itself stays as it always was (v0 by default, every option open); the others
# carry `mode=`, so an option that contradicts the rung is refused.
for _mode in MODES:
    if _mode["id"] not in registry:
        register(
            id=_mode["id"],
            entry_point="chopperscape.env:registered",
            vector_entry_point="chopperscape.vector:VectorEnv",
            max_episode_steps=10_000,
            kwargs={"mode": _mode["name"]},
        )
