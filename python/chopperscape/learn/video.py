"""Videos of played episodes, for ``python -m chopperscape.learn.evaluate --video``: GIF through Pillow, MP4 through
the ``ffmpeg`` program.

Episodes are replayed from their actions on an env that observes features (the rules decide everything; the
observation options do not), and each frame is the env's ``render()`` (600 × 800, the text HUD), as the command
line's ``record`` draws them. Frames are streamed: Pillow's own animated-GIF writer holds every frame until the
end (2 GB for a 4,000-step episode), so each frame is written as it comes, with Pillow's frame encoder
(``GifImagePlugin.getdata``), as the rectangle that changed since the previous frame under its own palette.
The file is written under a temporary name beside the destination and renamed when complete.
"""

from __future__ import annotations

import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from .. import _atomic

#: Frames a second, as the command line's recordings.
FPS = 30
#: Options that only shape the observation: the replay observes features and draws with `render()`.
OBSERVATION_OPTIONS = ("obs_type", "obs_size", "frame_stack", "hud", "keep_dim")
FORMATS = (".gif", ".mp4")


def check_destination(path: Path) -> None:
    """`ValueError` (before anything is played) for an extension other than .gif or .mp4, a missing folder, or
    .mp4 without ffmpeg."""
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise ValueError(f"--video {str(path)!r}: give a .gif or .mp4 file")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise ValueError(f"--video {str(path)!r}: the folder {str(folder)!r} does not exist")
    if suffix == ".mp4" and shutil.which("ffmpeg") is None:
        raise ValueError(
            f"--video {str(path)!r}: writing .mp4 needs the ffmpeg program on PATH (install ffmpeg, or write a .gif)"
        )


def frames(options: dict[str, Any], episodes: list[dict[str, Any]]) -> Iterator[np.ndarray]:
    """Every frame of `episodes` (each a `play_episodes` result with `seed` and `actions`): after reset and after
    each action."""
    from ..env import ChopperScapeEnv

    # The env itself never truncates (it takes no max_episode_steps): each episode's actions end where it ended.
    rules = {k: v for k, v in options.items() if k not in OBSERVATION_OPTIONS and k != "max_episode_steps"}
    env = ChopperScapeEnv(render_mode="rgb_array", obs_type="features", **rules)
    try:
        for episode in episodes:
            env.reset(seed=episode["seed"])
            yield _frame(env)
            for action in episode["actions"]:
                env.step(action)
                yield _frame(env)
    finally:
        env.close()


def write(path: Path, options: dict[str, Any], episodes: list[dict[str, Any]]) -> int:
    """Writes the episodes' frames to `path` (.gif or .mp4); returns the number of frames."""
    check_destination(path)
    with _atomic.replacing(path) as tmp:
        source = frames(options, episodes)
        return _write_gif(tmp, source) if path.suffix.lower() == ".gif" else _write_mp4(tmp, source)


def _delay_ms(i: int) -> int:
    """Frame `i`'s delay, so that frame `i` starts at `round(i · 100 / FPS)` hundredths (GIF's unit): 30 or 40 ms."""

    def at(i: int) -> int:
        return (i * 100 + FPS // 2) // FPS

    return 10 * (at(i + 1) - at(i))


def _write_gif(path: Path, source: Iterator[np.ndarray]) -> int:
    from PIL import GifImagePlugin, Image

    def indexed(rgb: np.ndarray) -> Image.Image:
        # The game's frames hold far fewer than 256 colours, so median cut keeps them exactly.
        return Image.fromarray(rgb).quantize(256, Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)

    previous: np.ndarray | None = None
    count = 0
    with open(path, "wb") as f:
        for rgb in source:
            if previous is None:
                first = indexed(rgb)
                header, _ = GifImagePlugin.getheader(first, info={"loop": 0})
                f.write(b"".join(header))
                part, offset = first, (0, 0)
            else:
                changed = np.any(rgb != previous, axis=2)
                rows, cols = np.flatnonzero(changed.any(axis=1)), np.flatnonzero(changed.any(axis=0))
                if len(rows) == 0:  # nothing moved: one unchanged pixel carries the frame's delay
                    rows, cols = np.array([0]), np.array([0])
                top, bottom, left, right = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
                part, offset = indexed(np.ascontiguousarray(rgb[top:bottom, left:right])), (int(left), int(top))
            for chunk in GifImagePlugin.getdata(part, offset, duration=_delay_ms(count), include_color_table=True):
                f.write(chunk)
            previous = rgb
            count += 1
        f.write(b";")
    return count


def _write_mp4(path: Path, source: Iterator[np.ndarray]) -> int:
    first = next(source)
    h, w, _ = first.shape
    cmd = [
        "ffmpeg",
        "-loglevel",
        "error",
        "-y",
        "-f",
        "rawvideo",
        "-pix_fmt",
        "rgb24",
        "-s",
        f"{w}x{h}",
        "-r",
        str(FPS),
        "-i",
        "-",
        "-c:v",
        "libx264",
        "-pix_fmt",
        "yuv420p",
        "-f",
        "mp4",
        str(path),
    ]
    count = 0
    # ffmpeg says little (-loglevel error), so its standard error is read once it has all the frames.
    with subprocess.Popen(cmd, stdin=subprocess.PIPE, stderr=subprocess.PIPE) as proc:
        assert proc.stdin is not None and proc.stderr is not None
        try:
            for rgb in _chain(first, source):
                proc.stdin.write(rgb.tobytes())
                count += 1
            proc.stdin.close()
        except BrokenPipeError:
            pass
        stderr = proc.stderr.read().decode(errors="replace")
        status = proc.wait()
    if status != 0:
        raise OSError(f"ffmpeg exited with status {status}: {stderr.strip()[-500:]}")
    return count


def _chain(first: np.ndarray, rest: Iterator[np.ndarray]) -> Iterator[np.ndarray]:
    yield first
    yield from rest


def _frame(env: Any) -> np.ndarray:
    """The env's rgb_array frame (never None: the env is made with render_mode="rgb_array")."""
    frame = env.render()
    assert frame is not None
    return frame
