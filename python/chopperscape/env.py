"""`ChopperScapeEnv`: the Gymnasium environment, a thin layer over the Rust core (`chopperscape._core.Env`)."""

from __future__ import annotations

import dataclasses
import importlib.util
from typing import TYPE_CHECKING, Any, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.wrappers import OrderEnforcing, TimeLimit

if TYPE_CHECKING:
    from ._human import HumanWindow

from . import _core
from ._checks import time_limit
from ._spaces import channel_axis, check_reset_options, core_seed, observation_box

#: `render_mode="human"` draws with pygame; it is declared only where pygame is installed, so that
#: Gymnasium's checker (which tries every declared mode) passes everywhere.
HUMAN_AVAILABLE = importlib.util.find_spec("pygame") is not None


class ChopperScapeEnv(gym.Env):
    """ChopperScape-v0: fly a helicopter through a sky of birds, refuelling from rising fuel tanks.

    ## Description
    The game of the "ChopperScape" Gymnasium tutorial, made exact (see `docs/SPEC.md`). The chopper flies in a
    band of the 800 × 600 screen; birds appear at the right edge and fly left; fuel tanks rise from the bottom.
    Every step burns one unit of fuel; touching a fuel tank refills it; touching a bird ends the episode.
    The game runs in Rust; every step is one call into it.

    ## Action Space
    `Discrete(5)`:

    | Num | Action     | Effect |
    |-----|------------|--------|
    | 0   | Right      | x += 5 |
    | 1   | Left       | x −= 5 |
    | 2   | Down       | y += 5 |
    | 3   | Up         | y −= 5 |
    | 4   | Do Nothing | —      |

    ## Observation Space
    Chosen by `obs_type`:
    - `"rgb"` (default): `Box(0, 255, (H, W, 3), uint8)`, the rendered frame, HUD included (see below);
    - `"rgb_float"`: `Box(0, 1, (H, W, 3), float32)`;
    - `"grayscale"`: `Box(0, 255, (H, W), uint8)` (`(H, W, 1)` with `keep_dim=True`);
    - `"features"`: `Box(low, high, (46,), float32)`, a description of the state (layout version 2):

    | Index | Name | Min | Max |
    |-------|------|-----|-----|
    | 0 | chopper x, `(x − 0) / 736` | 0 | 1 |
    | 1 | chopper y, `(y − 60) / 416` | 0 | 1 |
    | 2 | fuel left / max_fuel | 0 | 1 |
    | 3 | lives left / lives | 0 | 1 |
    | 4–19 | 4 birds that can still hit, soonest first: present, dx / 800, dy / 480 (centre to centre), in_lane | 0, −1, −1, 0 | 1, 1, 1, 1 |
    | 20–27 | 2 fuel tanks that can still be caught, nearest first: present, dx, dy, reachable | 0, −1, −1, 0 | 1, 1, 1, 1 |
    | 28–37 | 2 alien birds that can still hit: present, dx, dy, in_lane, next_shot (steps / 40) | 0, −1, −1, 0, 0 | 1, 1, 1, 1, 1 |
    | 38–45 | 2 missiles that can still hit: present, dx, dy, in_lane | 0, −1, −1, 0 | 1, 1, 1, 1 |

    `in_lane` is 1 when the hazard's row overlaps the chopper's (it hits unless one of them changes row);
    `reachable` is 1 when flying straight sideways catches the tank before it rises past. Hazards that have passed
    the chopper and tanks that have risen past it take no slot. The exact definitions and the version history are
    in the Rust docs of `chopperscape::features`.

    `obs_size=(H, W)` (default `(600, 800)`) draws pixel observations at that size; `frame_stack=k` stacks the
    last `k` observations on the last axis (`(46·k,)` for features).

    **The agent view** (pixel layout version 3, `chopperscape.PIXELS_VERSION`). Frames smaller than 300 × 400
    (84 × 84, 42 × 42) draw each entity as a solid box in its kind's grey level, at least 3 × 3 pixels, so that a
    small CNN sees every bird and tank: bird 0, alien 32, missile 64, chopper 112, fuel tank 176 on the white
    (255) sky (`look="auto"`). `look="art"` draws the tutorial's sprites at every size (version 2),
    `look="agent"` the boxes at every size; `render()` always shows the art.

    **The HUD in pixel observations**, in the
    `⌊H / 10⌋` rows above the flight band. Frames at least 300 × 400 show the tutorial's text line
    `Fuel Left: N | Rewards: N | Lives: N`. Smaller frames, where that text is illegible, show two bars a network
    can read instead (`hud_style="auto"`): at 84 × 84 the fuel bar fills rows 1–3 and the lives bar rows 5–6,
    all 84 columns. A bar showing `v` of `m` (`fuel` of `max_fuel`, `lives` left of `lives`) holds
    `I = round(255 · 84 · v / m)` units of ink from the left: black pixels, one grey pixel of level
    `255 − (I mod 255)`, then white. Decode one row with `I = sum(255 − row)` and `v = I · m / (255 · 84)`:
    fuel to within 0.003 % of `max_fuel`, lives exactly. The same grey levels appear in rgb (`(g, g, g)`) and
    grayscale. `hud_style="text"` draws the text at every size (version 1 with `look="art"`), `"gauge"` the bars at every size
    (`render()` included); `hud=False` draws no HUD. Other sizes and the exact layout: `docs/SPEC.md`.

    ## Rewards
    +1 for every step; −10 for a step in which a bird (or alien, or missile) hits the chopper. With
    `frame_skip=k` the rewards of the repeated steps are summed.

    ## Starting State
    Fuel `max_fuel` (1000); no birds, no tanks; the chopper at x uniform in [40, 80), y uniform in [90, 120).

    ## Episode End
    Termination: a bird hits the chopper with no life left to lose (`info["cause"] == "bird"`), or the fuel runs
    out (`info["cause"] == "fuel"`).

    Truncation: after 10,000 steps, by Gymnasium's `TimeLimit` wrapper that `gymnasium.make` adds
    (`max_episode_steps=10000`). The class itself never truncates.

    ## Arguments
    ```python
    import gymnasium as gym
    import chopperscape
    env = gym.make("ChopperScape-v0", obs_type="grayscale", obs_size=(84, 84), render_mode="rgb_array")
    ```

    | Argument | Default | Allowed |
    |----------|---------|---------|
    | `obs_type` | `"rgb"` | `"rgb"`, `"rgb_float"`, `"grayscale"`, `"features"` |
    | `obs_size` | `(600, 800)` | `(H, W)`, each in 8..=4096 |
    | `frame_stack` | 1 | 1..=64 |
    | `hud` | `True` | `True`, `False`: draw the HUD (fuel and lives, see above) into pixel observations |
    | `hud_style` | `"auto"` | `"auto"` (text in frames of at least 300 × 400, bars below), `"text"`, `"gauge"`; `render()` shows the text unless `"gauge"` |
    | `look` | `"auto"` | `"auto"` (the art in frames of at least 300 × 400, the agent view below), `"art"`, `"agent"`; `render()` always shows the art |
    | `keep_dim` | `False` | give `"grayscale"` without stacking a channel axis, `(H, W, 1)` instead of `(H, W)` (what CNN policies such as SB3's `CnnPolicy` expect; a view, no copy) |
    | `mode` | `None` | `None`, `"v0"`, `"sticky-v0"`, `"full-v0"`: a difficulty mode of ChopperScape-Bench (`chopperscape.MODES`), which fixes every rules option below (an option given beside it must agree); `gymnasium.make("ChopperScape-Sticky-v0")` and `"ChopperScape-Full-v0"` give it |
    | `lives` | 1 | 1..=1000 |
    | `bird_fuel_collision` | `"pass"` | `"pass"`, `"destroy"` |
    | `alien_prob` | 0 | [0, 1] |
    | `frame_skip` | 1 | 1..=1000 |
    | `sticky_prob` | 0 | [0, 1] |
    | `bird_prob` | 0.01 | [0, 1] |
    | `fuel_prob` | 0.01 | [0, 1] |
    | `max_fuel` | 1000 | 1..=1000000 |
    | `max_episode_steps` | 10000 | 1..=4294967295: an argument of `gymnasium.make` (the `TimeLimit` it adds, see Episode End), not of this class, which refuses it |
    | `render_mode` | `None` | `None`, `"rgb_array"` (600 × 800 × 3 frames), `"human"` (a pygame window, 30 fps; declared only where pygame is installed) |

    An unknown option or a value out of range raises `ValueError` naming the option and its range.

    ## Seeding
    `reset(seed=s)` seeds the game's generator with `s` (the same trajectory as the Rust `reset(Some(s))`);
    `reset()` continues the stream; the first `reset()` without any seed draws one from `np_random`, which
    Gymnasium seeds from OS entropy.

    ## Saving and restoring a state
    `chopperscape.clone_state(env)` returns the whole game state as bytes; `chopperscape.restore_state(env, state)`
    puts the game back in it *and* rewinds the wrappers that count steps: the `TimeLimit` that `gymnasium.make`
    adds counts from the restored state's step, so truncation comes exactly when it would have. Pass the env
    `gymnasium.make` returned. `env.unwrapped.restore_state(state)` cannot reach the wrappers, so on an
    environment made by `gymnasium.make` it raises `RuntimeError` pointing here (on a `ChopperScapeEnv` you
    built yourself, it restores).

    ## Version History
    - v0: the tutorial's game with its contradictions resolved as SPEC.md states.
    - ChopperScape-Sticky-v0, ChopperScape-Full-v0 (modes `sticky-v0`, `full-v0`): the v0 game with fixed
      options: frame skip 4 and sticky actions 0.25 (as ALE v5); and with 3 lives, aliens (0.005) and bird–fuel
      collisions. See `docs/SPEC.md`, "Difficulty modes".
    """  # noqa: E501 - the Markdown tables above cannot wrap

    metadata = {  # noqa: RUF012 - Gymnasium declares `metadata` a plain attribute
        "render_modes": (["human"] if HUMAN_AVAILABLE else []) + ["rgb_array"],
        "render_fps": _core.RENDER_FPS,
    }

    def __init__(self, render_mode: str | None = None, keep_dim: bool = False, **options: Any):
        if render_mode == "human" and not HUMAN_AVAILABLE:
            raise ValueError(
                "option `render_mode`='human' needs pygame, which is not installed: pip install pygame "
                "(or use render_mode='rgb_array')"
            )
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"invalid value {render_mode!r} for option `render_mode`: allowed None, 'human', 'rgb_array'"
            )
        if "max_episode_steps" in options:
            raise ValueError(
                "option `max_episode_steps` belongs to gymnasium.make(..., max_episode_steps=N) (the TimeLimit "
                "wrapper), not to the environment"
            )
        self._options = dict(options)
        self._core = _core.Env({**options, "max_episode_steps": None})
        self.render_mode = render_mode
        self.action_space = spaces.Discrete(len(_core.ACTION_MEANINGS))
        self._keep_dim = channel_axis(keep_dim, self._core)
        self.observation_space = observation_box(self._core, self._keep_dim)
        self._stream_started = False
        self._window: HumanWindow | None = None
        #: Set by the registered entry point: `gymnasium.make` wraps this env in a `TimeLimit`.
        self._made_by_gymnasium = False

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Starts an episode. `seed` reseeds; no seed continues the stream (see Seeding). `options` must be empty:
        ChopperScape's reset takes none (`ValueError` otherwise, as `VectorEnv.reset`)."""
        check_reset_options(options)
        if seed is not None:
            core = core_seed(seed)
            super().reset(seed=int(seed))
        elif not self._stream_started:
            super().reset()
            core = int(self.np_random.integers(0, 2**63))
        else:
            super().reset()
            core = None
        obs, info = self._core.reset(core)
        self._stream_started = True
        if self.render_mode == "human":
            self.render()
        return (obs[..., None] if self._keep_dim else obs), info

    def step(self, action: Any) -> tuple[np.ndarray, SupportsFloat, bool, bool, dict[str, Any]]:
        """One step: `(obs, reward: float, terminated: bool, truncated: bool, info)`."""
        obs, reward, terminated, truncated, info = self._core.step(action)
        if self.render_mode == "human":
            self.render()
        return (obs[..., None] if self._keep_dim else obs), reward, terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """The 600 × 800 × 3 frame (`"rgb_array"`), or shows it in a window (`"human"`)."""
        if self.render_mode is None:
            gym.logger.warn(
                "You are calling render method without specifying any render mode. "
                'You can specify the render_mode at initialization, e.g. gym.make("ChopperScape-v0", '
                'render_mode="rgb_array")'
            )
            return None
        frame = self._core.render()
        if self.render_mode == "rgb_array":
            return frame
        if self._window is None:
            from ._human import HumanWindow

            self._window = HumanWindow(self.metadata["render_fps"])
        self._window.show(frame)
        return None

    def close(self) -> None:
        """Closes the window, if any. Calling it again is fine."""
        if self._window is not None:
            self._window.close()
            self._window = None

    def get_action_meanings(self) -> list[str]:
        """The name of each action, by index: `["Right", "Left", "Down", "Up", "Do Nothing"]`."""
        return list(_core.ACTION_MEANINGS)

    def get_keys_to_action(self) -> dict[tuple[str, ...], int]:
        """Keys for `gymnasium.utils.play.play`: W A S D move, and no key is action 4 (pass `noop=4` to `play`)."""
        return {("d",): 0, ("a",): 1, ("s",): 2, ("w",): 3}

    def clone_state(self) -> bytes:
        """The whole game state (options included) as bytes: keep it, save it, restore it later."""
        return self._core.snapshot()

    def restore_state(self, state: bytes) -> None:
        """Restores a state from `clone_state()`; `ValueError` for bytes that are not a snapshot of this
        environment's options. The environment then continues exactly as it would have from that state.

        On an environment made by `gymnasium.make` this raises `RuntimeError`: the `TimeLimit` wrapper's step
        counter would not be rewound. Use `chopperscape.restore_state(env, state)` there (see the class docs)."""
        if self._made_by_gymnasium:
            raise RuntimeError(
                "restore_state on the unwrapped env would leave the TimeLimit wrapper that gymnasium.make added "
                "counting from the wrong step: call chopperscape.restore_state(env, state) with the env "
                "gymnasium.make returned"
            )
        self._restore(state)

    def _restore(self, state: bytes) -> None:
        self._core.restore(bytes(state))
        self._stream_started = True

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_window"] = None
        return state


def registered(**kwargs: Any) -> ChopperScapeEnv:
    """The entry point of `ChopperScape-v0`: a `ChopperScapeEnv` that knows `gymnasium.make` wraps it."""
    env = ChopperScapeEnv(**kwargs)
    env._made_by_gymnasium = True
    return env


def clone_state(env: gym.Env) -> bytes:
    """The whole game state of `env` (a `ChopperScapeEnv`, wrapped or not) as bytes; the step count since the
    last reset is part of it."""
    base = env.unwrapped
    if not isinstance(base, ChopperScapeEnv):
        raise TypeError(f"clone_state needs a ChopperScape-v0 environment, got {type(base).__name__}")
    return base.clone_state()


def restore_state(env: gym.Env, state: bytes) -> None:
    """Restores `state` (from `clone_state`) into `env` and rewinds every wrapper that counts steps: each
    `TimeLimit` then counts from the state's step. Pass the env that `gymnasium.make` returned (an unwrapped
    `ChopperScapeEnv` works too). `ValueError` for bytes that are not a state of these options; nothing changes
    then. An env never reset is reset first through its wrappers (Gymnasium's order enforcing and env checker
    want a reset before the first step); the restore then replaces everything that reset did."""
    base = env.unwrapped
    if not isinstance(base, ChopperScapeEnv):
        raise TypeError(f"restore_state needs a ChopperScape-v0 environment, got {type(base).__name__}")
    base._core.restore(bytes(state))  # checks the bytes against these options before anything changes
    layer = env
    while isinstance(layer, gym.Wrapper):
        if isinstance(layer, OrderEnforcing) and not layer.has_reset:
            env.reset()
            break
        layer = layer.env
    base._restore(state)
    steps = base._core.elapsed_steps
    layer = env
    while isinstance(layer, gym.Wrapper):
        if isinstance(layer, TimeLimit):
            layer._elapsed_steps = steps  # type: ignore[assignment]  # Gymnasium annotates it as None
        layer = layer.env


def make_env(max_episode_steps: int | None = 10_000, **options: Any) -> gym.Env:
    """`gymnasium.make("ChopperScape-v0", **options)` truncated at `max_episode_steps`, where `None` means no time
    limit at all (`gymnasium.make`'s own `max_episode_steps=None` falls back to the registered 10,000): the env's
    spec then says `max_episode_steps=None` too, so a Minari dataset recovers the same env."""
    limit = time_limit(max_episode_steps)
    spec = dataclasses.replace(gym.spec("ChopperScape-v0"), max_episode_steps=limit)
    return gym.make(spec, **options)
