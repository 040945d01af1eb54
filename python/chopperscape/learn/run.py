"""A training run's life around the loop: :class:`Run`, the one context manager that opens the run folder (a new
run, `--force`, or `--resume`), builds the envs, the recipe's parts and the :class:`~.state.TrainState`, writes the
progress rows and the checkpoints, saves the model when the run ends (its budget, `--minutes` or a signal), and
closes everything whatever happens.

The folder: ``recipe.json``, ``progress.csv``, ``model.pt`` (:mod:`.modelfile`) and ``resume.pt`` (:mod:`.state`).
A folder that already holds a run is refused unless `force`, which first moves that run whole into
``OUT/replaced-N`` (the first free N) and only then starts the new run there: a run folder never mixes files of two
runs, and the old run is never lost. Every file is written whole or not at all (:mod:`chopperscape._atomic`); one
that cannot be written ends the run with a :class:`RunWriteError` naming it. Ctrl-C (SIGINT, SIGTERM, SIGHUP) is
deferred: the run stops after the current update, saves, and :class:`chopperscape._signals.Interrupted` follows.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
from collections.abc import Iterator
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import torch

from .. import _atomic, _signals
from ..vector import VectorEnv
from . import progress
from .modelfile import save
from .normalize import RewardScaler
from .parts import Parts, parts_of
from .recipe import Recipe
from .rollout import Episodes
from .rundir import RUN_FILES, RunLock, check_run_folder, remove_stale_parts
from .state import Clock, EnvBatch, TorchRng, TrainState, read_resume

#: Updates between checkpoints (`model.pt` and `resume.pt`).
CHECKPOINT_EVERY = 50


class RunWriteError(OSError):
    """A file of the run could not be written (a read-only folder, a full disk): the message names it."""


@contextlib.contextmanager
def _writing(path: Path, after: str = "") -> Iterator[None]:
    """`OSError` in the block as a `RunWriteError` naming `path` (and what is kept, `after`)."""
    try:
        yield
    except RunWriteError:
        raise
    except OSError as e:
        raise RunWriteError(f"cannot write {path}: {e.strerror or e}{after}") from None


def _next_aside(out: Path) -> Path:
    """The first free `OUT/replaced-N` (N = 1, 2, …): where `--force` keeps the run it replaces."""
    n = 1
    while os.path.lexists(out / f"replaced-{n}"):
        n += 1
    return out / f"replaced-{n}"


def start_run(out: Path, recipe: Recipe) -> tuple[progress.Writer, Path | None]:
    """Makes the run folder `out` ready for a new run and writes its `recipe.json` and the progress header:
    a run already there (`--force`) is first moved whole into `OUT/replaced-N`, so that `out` never holds files of
    two runs. Returns the progress writer and where the old run went (None if there was none). On a write
    error (`RunWriteError`, `ValueError` for an `out` that cannot be a folder), nothing new is left behind and an
    old run is moved back."""
    made = not os.path.lexists(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ValueError(f"--out {out}: cannot make the folder: {e.strerror or e}") from None
    old = [name for name in RUN_FILES if os.path.lexists(out / name)]
    aside = _next_aside(out) if old else None
    moved: list[str] = []
    try:
        if aside is not None:
            with _writing(aside):
                aside.mkdir()
                for name in old:
                    os.replace(out / name, aside / name)
                    moved.append(name)
        with _writing(out / "recipe.json"):
            _atomic.write_text(out / "recipe.json", json.dumps(asdict(recipe), indent=2) + "\n")
        with _writing(out / "progress.csv"):
            return progress.Writer(out / "progress.csv"), aside
    except BaseException:
        for name in ("progress.csv", "recipe.json"):
            with contextlib.suppress(OSError):
                if name not in old or name in moved:
                    os.unlink(out / name)
        for name in moved:
            with contextlib.suppress(OSError):
                os.replace(aside / name, out / name)  # type: ignore[operator]
        with contextlib.suppress(OSError):
            if aside is not None:
                aside.rmdir()
            if made:
                out.rmdir()
        raise


#: What the end of a run says it kept when a later file cannot be written.
_KEPT = "; the model saved last is kept"


class Run(contextlib.AbstractContextManager["Run"]):
    """A run of `recipe` in the folder `out`: ``with Run(...) as run:`` gives `run.state` (the training state,
    restored from `resume.pt` with `resume`) and `run.parts` (the recipe's parts); leaving the block saves the
    model and the resume state (unless an exception ends it) and closes the envs, the guidance and the progress
    file. `ValueError` before anything is written for a folder that holds a run (unless `force`), a resume state
    that is missing or another run's, or a recipe too large for memory."""

    def __init__(self, recipe: Recipe, out: Path, force: bool = False, resume: bool = False):
        self.recipe, self.out = recipe, Path(out)
        self.model_path = self.out / "model.pt"
        self._closing = contextlib.ExitStack()
        try:
            # The folder is this process's for the run's life (a second writer is refused by name), and what a
            # killed run left half-written goes before anything is read or written.
            self._closing.enter_context(RunLock(self.out))
            saved = read_resume(self.out / "resume.pt", recipe) if resume else None
            if not resume:
                check_run_folder(self.out, force)
            teacher = None
            if recipe.teacher:
                from .guidance import load_teacher

                teacher = load_teacher(recipe)
            remove_stale_parts(self.out)
            self.state, self.parts = self._build(recipe, teacher, saved)
            if resume:
                self.writer, aside = progress.Writer.resume(self.out / "progress.csv", self.state.env_steps), None
            else:
                self.writer, aside = start_run(self.out, recipe)
            self._closing.callback(self._close_writer)
        except BaseException:
            self._closing.close()
            raise
        if aside is not None:
            print(f"note: --force: the run that was in {self.out} is kept in {aside}", file=sys.stderr)
        self.stop = _signals.defer()  # Ctrl-C ends the run after the current update, which is then saved
        self._closing.callback(self.stop.restore)
        self.state.clock.restart()

    def _build(self, recipe: Recipe, teacher: Any, saved: dict | None) -> tuple[TrainState, Parts]:
        torch.manual_seed(recipe.seed)
        torch.set_num_threads(recipe.torch_threads)
        rng = np.random.default_rng(recipe.seed)
        options = recipe.env_options
        envs = VectorEnv(recipe.num_envs, num_threads=recipe.env_threads, obs_type=recipe.obs_type, **options)
        self._closing.callback(envs.close)
        parts = parts_of(recipe, envs, teacher)
        self._closing.callback(parts.guide.close)
        params = list(parts.agent.parameters()) + parts.guide.params + parts.frames_loss.params + parts.novelty.params
        n = recipe.num_envs
        state = TrainState(
            agent=parts.agent,
            optimizer=torch.optim.Adam(params, lr=recipe.learning_rate, eps=1e-5),
            obs_norm=parts.obs_norm,
            rewards=RewardScaler(n, recipe.gamma, recipe.norm_reward),
            episodes=Episodes(n),
            envs=EnvBatch(envs),
            guidance=parts.guide,
            frames_loss=parts.frames_loss,
            novelty=parts.novelty,
            rng=rng,
            torch_rng=TorchRng(),
            clock=Clock(),
            next_obs=torch.zeros((n, *parts.obs_shape), dtype=parts.obs_dtype, device=parts.device),
            next_done=np.zeros(n, bool),
        )
        if saved is None:
            raw, _ = envs.reset(seed=recipe.seed)
            state.next_obs = parts.encode(raw)
            parts.guide.reset(recipe.seed)
        else:
            try:
                state.load_state_dict(saved)
            except ValueError as e:
                raise ValueError(f"--resume {self.out}: resume.pt does not fit this run's recipe ({e})") from None
        return state, parts

    @property
    def envs(self) -> VectorEnv:
        return self.state.envs.envs

    def stopping(self, minutes: float | None) -> bool:
        """Whether the run should stop before its next update: a signal came, or `minutes` of this process's wall
        time have passed (the schedules still follow env steps, so a run cut short is the prefix of the whole)."""
        return self.stop.pending is not None or (minutes is not None and self.state.clock.elapsed() >= minutes * 60)

    def log(self, row: dict[str, Any]) -> None:
        """Writes the update's progress row (with the run's wall time) and, every `CHECKPOINT_EVERY` updates, a
        checkpoint."""
        with _writing(self.out / "progress.csv", _KEPT):
            self.writer.row({"wall_s": f"{self.state.clock.seconds():.1f}", **row})
        if self.state.update % CHECKPOINT_EVERY == 0:
            self.checkpoint()

    def checkpoint(self) -> None:
        """Saves the model (`model.pt`) and the state to go on from (`resume.pt`), each whole or not at all."""
        s = self.state
        with _writing(self.model_path, _KEPT):
            save(self.model_path, s.agent, s.obs_norm, self.recipe, self.parts.obs_shape, s.env_steps)
        path = self.out / "resume.pt"
        with _writing(path, _KEPT):
            s.save(path, self.recipe)

    def _close_writer(self) -> None:
        with contextlib.suppress(OSError):
            self.writer.close()

    def __exit__(self, exc_type, exc, tb) -> None:
        try:
            if exc_type is None:  # the end, a signal or --minutes: the model and the state, as they are now
                self.checkpoint()
        finally:
            self._closing.close()
        if exc_type is None:
            self.stop.check(
                f"the model reached so far ({self.state.env_steps} env steps) is saved in {self.model_path}"
            )
