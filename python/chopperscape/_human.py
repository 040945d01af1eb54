"""`render_mode="human"`: a pygame window, as Gymnasium's own environments do it.

The Rust window lives in the `chopperscape` command line program (`chopperscape play`), not in this wheel;
from Python the frame is shown with pygame, imported only when a human window is asked for.
"""

from __future__ import annotations

import os

import numpy as np
from gymnasium.error import DependencyNotInstalled


class HumanWindow:
    """A window that shows 600 × 800 RGB frames at `fps` frames per second."""

    def __init__(self, fps: int, title: str = "ChopperScape-v0"):
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        try:
            import pygame
        except ImportError as e:
            raise DependencyNotInstalled(
                'render_mode="human" needs pygame: pip install pygame (or pip install "chopperscape[human]"); '
                'render_mode="rgb_array" needs nothing more'
            ) from e
        self._pygame = pygame
        pygame.display.init()
        pygame.display.set_caption(title)
        self._screen = pygame.display.set_mode((800, 600))
        self._clock = pygame.time.Clock()
        self._fps = fps

    def show(self, frame: np.ndarray) -> None:
        """Draws `frame` (600 × 800 × 3 uint8) and waits for the next tick of the frame clock."""
        pygame = self._pygame
        pygame.event.pump()
        surface = pygame.surfarray.make_surface(np.transpose(frame, (1, 0, 2)))
        self._screen.blit(surface, (0, 0))
        pygame.display.flip()
        self._clock.tick(self._fps)

    def close(self) -> None:
        """Closes the window."""
        self._pygame.display.quit()
