"""Type stubs of the compiled module `chopperscape._core` (crates/python)."""

from collections.abc import Sequence
from typing import Any, final

import numpy as np
import numpy.typing as npt

ACTION_MEANINGS: list[str]
OPTION_NAMES: list[str]
#: Every option of the core, in OPTION_NAMES order, described once: `name`, `default` (text, as `option_value`
#: reads it), `allowed` (in words, as the errors say), `doc` (one line) and `rule` (a rules option, as action logs
#: record, rather than an observation setting).
OPTIONS: list[dict[str, Any]]
#: The difficulty modes of ChopperScape-Bench, easiest first, each `name` (what `mode=` takes), `id` (its Gymnasium
#: id), `doc` (one line) and `options` (the rules options it sets, as text; every other rules option keeps its
#: default).
MODES: list[dict[str, Any]]
CAUSE_NAMES: list[str]
SNAPSHOT_VERSION: int
#: The layout version of the `"features"` observation (the Rust docs of `chopperscape::features` give the history).
FEATURES_VERSION: int
#: The version of what pixel observations show: 3 draws the agent view in frames under 300 × 400 (`look="auto"`),
#: 2 the gauges there (`hud_style="auto"`), 1 the text line at every size (docs/SPEC.md, "HUD and pixel layout").
PIXELS_VERSION: int
#: The options that draw each pixel layout version (`chopperscape::render::layout_options`): an older model is
#: shown its own.
PIXEL_LAYOUTS: dict[int, dict[str, str]]
RENDER_FPS: int
#: The built-in policies' names, as the command line's `--policy` takes them.
POLICY_NAMES: list[str]
#: The most memory one environment's observation buffers may take (bytes); options over it raise ValueError.
MAX_ENV_BYTES: int
#: The most memory one VectorEnv may take (bytes); batches over it raise ValueError.
MAX_BATCH_BYTES: int
#: The most worker threads a VectorEnv may ask for.
MAX_THREADS: int
#: The largest action log `read_action_log` reads (bytes), as `chopperscape replay`.
MAX_LOG_BYTES: int
__version__: str

def option_value(name: str, text: str) -> Any:
    """Option `name` written as command-line text (`84x84`, `false`, `none`), typed by the core's parser:
    int, float, str, bool, an (h, w) tuple or None. ValueError naming the option and what it allows."""

def read_action_log(path: str) -> dict[str, Any]:
    """The action log at `path`, read and checked by the command line's reader (at most MAX_LOG_BYTES):
    seed, options (rules as text, but max_episode_steps), max_episode_steps, actions (bytes), steps, return,
    cause, policy. ValueError naming the file and what is wrong."""

#: Stub-only aliases (not at runtime): one env's info dict, and what a batch call returns.
Info = dict[str, Any]

@final
class Env:
    """One ChopperScape environment, as the core runs it; every method returns fresh arrays."""

    def __new__(cls, options: dict[str, Any] | None = None) -> Env: ...
    def reset(self, seed: int | None = None) -> tuple[npt.NDArray[Any], Info]: ...
    def step(self, action: Any) -> tuple[npt.NDArray[Any], float, bool, bool, Info]: ...
    def render(self) -> npt.NDArray[np.uint8]: ...
    def info(self) -> Info: ...
    @property
    def obs_shape(self) -> list[int]: ...
    @property
    def obs_dtype(self) -> str: ...
    @property
    def obs_bounds(self) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """One period of the bounds: one value each when uniform, else repeated over the flat observation."""
    @property
    def elapsed_steps(self) -> int:
        """Steps taken in the current episode."""
    def snapshot(self) -> bytes: ...
    def restore(self, data: bytes) -> None: ...
    @staticmethod
    def from_snapshot(data: bytes) -> Env: ...
    def __reduce__(self) -> tuple[Any, tuple[bytes]]: ...

BatchOutputs = tuple[
    npt.NDArray[Any],  # observations, (num_envs, *obs_shape)
    npt.NDArray[np.float64],  # rewards
    npt.NDArray[np.bool_],  # terminated
    npt.NDArray[np.bool_],  # truncated
    npt.NDArray[np.int64],  # fuel
    npt.NDArray[np.int64],  # lives
    npt.NDArray[np.uint8],  # cause codes, CAUSE_NAMES
    npt.NDArray[Any] | None,  # final observations (SAME_STEP), else None
]

@final
class VectorEnv:
    """`num_envs` environments stepped together with the GIL released; environment i of a batch reset with
    seed s is seeded s + i. With copy=False every call returns the same read-only views of the output arrays."""

    def __new__(
        cls,
        num_envs: int,
        num_threads: int | None = None,
        options: dict[str, Any] | None = None,
        same_step: bool = False,
        copy: bool = True,
        time_limit: int | None = None,
    ) -> VectorEnv: ...
    def reset(self, seed: int | None = None) -> BatchOutputs: ...
    def reset_seeds(self, seeds: Sequence[int | None]) -> BatchOutputs: ...
    def step(self, actions: npt.NDArray[np.int64]) -> BatchOutputs: ...
    def render(self, i: int) -> npt.NDArray[np.uint8]: ...
    def snapshot(self, i: int) -> bytes: ...
    def state(self) -> tuple[bool, list[tuple[bytes, bool, int]]]: ...
    def set_state(self, started: bool, envs: Sequence[tuple[bytes, bool, int]]) -> None: ...
    @property
    def num_envs(self) -> int: ...
    @property
    def num_threads(self) -> int: ...
    @property
    def obs_shape(self) -> list[int]: ...
    @property
    def obs_dtype(self) -> str: ...
    @property
    def obs_bounds(self) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]: ...
    @property
    def max_fuel(self) -> int: ...
    @property
    def lives(self) -> int: ...

def _panic(message: str) -> None: ...

@final
class Policy:
    """A built-in policy (`random`, `heuristic`, or a fixed action) reading one `Env`'s world."""

    def __new__(cls, name: str, seed: int = 0) -> Policy: ...
    def act(self, env: Env) -> int: ...
    def reset(self, seed: int | None = None) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def seed(self) -> int: ...

@final
class VectorPolicy:
    """One built-in policy per environment of a `VectorEnv`; policy i is seeded seed + i."""

    def __new__(cls, name: str, num_envs: int, seed: int = 0) -> VectorPolicy: ...
    def act(self, envs: VectorEnv) -> npt.NDArray[np.int64]: ...
    def reset(self, seed: int | None = None) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def num_envs(self) -> int: ...
    @property
    def seed(self) -> int: ...
