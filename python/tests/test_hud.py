"""The HUD at agent resolution: a small fixed decoder reads `info["fuel"]` (within ±2 % of `max_fuel`, in fact
within half a unit of ink) and `info["lives"]` (exactly) back from one 84 × 84 grayscale frame, as SPEC.md's
"HUD and pixel layout" section describes it.
"""

import gymnasium as gym
import numpy as np
import pytest

import chopperscape
from chopperscape import ChopperScapeEnv, VectorEnv

#: The bars at 84 × 84: (rows, columns) of the fuel bar and the lives bar.
FUEL_84 = (slice(1, 4), slice(0, 84))
LIVES_84 = (slice(5, 7), slice(0, 84))
#: The most a bar of 84 columns can be off, as a share of its full value: half a unit of ink.
HALF_INK_84 = 1 / (510 * 84)


def layout(h: int, w: int):
    """The bars of an `h × w` frame by SPEC.md's formula (None below 10 rows)."""
    b = 60 * h // 600
    if b == 0:
        return None
    if b == 1:
        return (slice(0, 1), slice(0, w // 2)), (slice(0, 1), slice(w // 2, w))
    return (slice(b // 8, b // 2), slice(0, w)), (slice(b // 2 + b // 8, b - b // 8), slice(0, w))


def decode(frame: np.ndarray, bar, full: int) -> float:
    """The value a bar shows out of `full`: ink = sum(255 - pixel) over its first row, value =
    ink * full / (255 * columns). Checks every row of the bar is the same (and, for rgb, every pixel grey)."""
    rows, cols = bar
    pixels = frame[rows, cols].astype(np.int64)
    if pixels.ndim == 3:
        assert (pixels == pixels[..., :1]).all(), "HUD pixels are grey"
        pixels = pixels[..., 0]
    assert (pixels == pixels[:1]).all(), "every row of a bar is the same"
    ink = int((255 - pixels[0]).sum())
    return ink * full / (255 * pixels.shape[1])


def test_the_layout_versions_are_exposed():
    assert chopperscape.PIXELS_VERSION == 3 and chopperscape.FEATURES_VERSION == 2
    assert chopperscape._core.SNAPSHOT_VERSION == 3


@pytest.mark.parametrize("max_fuel", [1000, 237])
def test_grayscale_frames_decode_to_info_fuel_at_every_level_and_to_info_lives(max_fuel):
    env = ChopperScapeEnv(
        obs_type="grayscale", obs_size=(84, 84), bird_prob=0.0, fuel_prob=0.0, lives=3, max_fuel=max_fuel
    )
    obs, info = env.reset(seed=0)
    levels = []
    while True:
        fuel = decode(obs, FUEL_84, max_fuel)
        assert abs(fuel - info["fuel"]) <= 0.02 * max_fuel
        assert abs(fuel - info["fuel"]) <= max_fuel * HALF_INK_84 + 1e-9, (info["fuel"], fuel)
        assert round(decode(obs, LIVES_84, 3)) == info["lives"] == 3
        levels.append(info["fuel"])
        obs, _, terminated, _, info = env.step(4)
        if terminated:
            assert info["fuel"] == 0 and decode(obs, FUEL_84, max_fuel) == 0
            levels.append(0)
            break
    assert levels == list(range(max_fuel, -1, -1)), "every level once"


def test_fuel_and_lives_decode_through_refuels_and_hits_in_a_stacked_vector_env():
    # Default rules with tanks and birds, five lives, random actions: the newest frame of each stack decodes.
    envs = VectorEnv(4, obs_type="grayscale", obs_size=(84, 84), frame_stack=4, lives=5, bird_prob=0.05)
    obs, info = envs.reset(seed=3)
    rng = np.random.default_rng(0)
    lives_seen, refuels = set(), 0
    last = info["fuel"].copy()
    for _ in range(1500):
        for i in range(4):
            newest = obs[i, :, :, -1]
            assert abs(decode(newest, FUEL_84, 1000) - info["fuel"][i]) <= 1000 * HALF_INK_84 + 1e-9
            assert round(decode(newest, LIVES_84, 5)) == info["lives"][i]
            lives_seen.add(int(info["lives"][i]))
        refuels += int((info["fuel"] > last).sum())
        last = info["fuel"].copy()
        obs, _, _, _, info = envs.step(rng.integers(0, 5, size=4))
    assert refuels > 0 and lives_seen >= {1, 2, 3, 4, 5}


def test_rgb_frames_carry_the_same_grey_bars():
    gray = ChopperScapeEnv(obs_type="grayscale", obs_size=(84, 84), lives=2)
    rgb = ChopperScapeEnv(obs_type="rgb", obs_size=(84, 84), lives=2)
    g, info = gray.reset(seed=1)
    c, _ = rgb.reset(seed=1)
    for t in range(200):
        assert np.array_equal(c[:8, :, 0], g[:8]) and np.array_equal(c[:8, :, 2], g[:8])
        assert round(decode(c, LIVES_84, 2)) == info["lives"]
        assert abs(decode(c, FUEL_84, 1000) - info["fuel"]) <= 1000 * HALF_INK_84 + 1e-9
        g, _, term, _, info = gray.step(t % 5)
        c, *_ = rgb.step(t % 5)
        if term:
            break


def test_text_gauge_and_auto_styles_and_what_render_shows():
    options = dict(obs_type="grayscale", obs_size=(84, 84))
    auto = ChopperScapeEnv(**options, render_mode="rgb_array")
    text = ChopperScapeEnv(**options, hud_style="text")
    off = ChopperScapeEnv(**options, hud=False)
    a, info = auto.reset(seed=4)
    t, _ = text.reset(seed=4)
    o, _ = off.reset(seed=4)
    assert decode(a, FUEL_84, 1000) == info["fuel"] == 1000
    assert not np.array_equal(a[:8], t[:8]), "the text of pixel layout 1 is not the bars"
    assert (o[:8] == 255).all() and np.array_equal(a[8:], o[8:]), "the HUD lies above the flight band only"
    # render() keeps the text at full size unless the gauges are asked for; then they decode there too.
    frame = auto.render()
    assert frame.shape == (600, 800, 3)
    gauge = gym.make("ChopperScape-v0", render_mode="rgb_array", hud_style="gauge", obs_type="features", lives=4)
    gauge.reset(seed=4)
    _, _, _, _, info = gauge.step(4)
    full = gauge.render()
    fuel_bar, lives_bar = layout(600, 800)
    assert abs(decode(full, fuel_bar, 1000) - info["fuel"]) <= 1000 / (510 * 800) + 1e-9
    assert round(decode(full, lives_bar, 4)) == 4
    assert not np.array_equal(full[:60], frame[:60])


@pytest.mark.parametrize("size", [(10, 8), (20, 13), (42, 42), (210, 160), (299, 399)])
def test_the_documented_layout_holds_at_other_sizes(size):
    env = ChopperScapeEnv(obs_type="grayscale", obs_size=size, fuel_prob=0.0, lives=3, max_fuel=90)
    fuel_bar, lives_bar = layout(*size)
    obs, info = env.reset(seed=2)
    for _ in range(100):
        assert abs(decode(obs, fuel_bar, 90) - info["fuel"]) <= 0.02 * 90
        assert round(decode(obs, lives_bar, 3)) == info["lives"]
        obs, _, term, _, info = env.step(4)
        if term:
            break


def test_hud_style_is_refused_by_name_when_unknown():
    with pytest.raises(ValueError, match=r"hud_style.*\"auto\", \"text\", \"gauge\""):
        ChopperScapeEnv(hud_style="bars")
    with pytest.raises(ValueError, match="hud_style"):
        VectorEnv(2, hud_style=1)
