"""The flags of ``python -m chopperscape.learn.train`` and the :class:`~chopperscape.learn.recipe.Recipe` they make,
every setting checked: shared by the training command and the seed runner (:mod:`chopperscape.learn.seeds`), which
checks the flags it passes on before any seed trains. Plain argparse over the recipe; no torch at import.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from .._cli import env_options
from ..modes import MODES, with_mode
from ..options import ENV_OPTIONS
from .recipe import (
    DEFAULT_STEPS,
    PRESETS,
    RECIPE_FLAGS,
    RESERVED_OPTIONS,
    Recipe,
    check_minutes,
    check_recipe,
    check_until,
    read_recipe,
)
from .rundir import check_run_folder

#: What ``--help`` says the command does.
DESCRIPTION = "Trains the PPO recipe on ChopperScape-v0 (CleanRL-style sections, PyTorch)."


def parse(args: list[str]) -> tuple[argparse.Namespace, Recipe]:
    """The training command's flags and the recipe they make, every setting checked (exit 2 through argparse,
    naming the setting): what `train.main` trains, and what the seed runner checks before it trains any seed."""
    p = _parser()
    a = p.parse_args(args)
    if a.resume is not None:
        return a, _resumed(p, a)
    if a.out is None:
        p.error("the following arguments are required: --out (or --resume DIR)")
    a.preset = a.preset or "features"
    preset = dict(PRESETS[a.preset])
    steps = a.steps if a.steps is not None else preset.pop("total_steps", DEFAULT_STEPS)
    preset.pop("total_steps", None)
    allowed = [n for n in ENV_OPTIONS if n not in RESERVED_OPTIONS]
    options = {**preset.pop("env_options", {}), **env_options(p, a.option, allowed=allowed, refused=RESERVED_OPTIONS)}
    if a.mode is not None:
        try:
            options = with_mode(a.mode, options)
        except ValueError as e:
            p.error(f"--mode {a.mode}: {e} (from --preset {a.preset} or --option)")
    defaults = Recipe()
    settings = {**{f: getattr(defaults, f) for f in RECIPE_FLAGS}, **preset}
    settings.update({f: getattr(a, f) for f in RECIPE_FLAGS if getattr(a, f) is not None})
    recipe = Recipe(
        **settings,
        env_options=options,
        norm_obs=not a.no_norm_obs,
        norm_reward=not a.no_norm_reward,
        invert_frames=not a.no_invert_frames,
        total_steps=steps,
    )
    try:
        check_recipe(recipe)
        check_minutes(a.minutes)
        check_until(a.until)
        check_run_folder(a.out, a.force)
    except ValueError as e:
        p.error(str(e))
    return a, recipe


def _parser() -> argparse.ArgumentParser:
    """The training command's flags: the run folder, the budget and stops, the preset and mode, every recipe
    setting (`RECIPE_FLAGS`), the switches."""
    p = argparse.ArgumentParser(prog="python -m chopperscape.learn.train", description=DESCRIPTION)
    p.add_argument(
        "--out",
        type=Path,
        default=None,
        help="folder for progress.csv, model.pt, recipe.json, resume.pt",
    )
    p.add_argument(
        "--resume",
        type=Path,
        default=None,
        metavar="DIR",
        help="continue the run in DIR from its last checkpoint (resume.pt, saved every 50 updates and when a run "
        "stops), with the recipe of its recipe.json: the curve goes on as the uninterrupted run's; only --minutes "
        "and --until may be given with it",
    )
    p.add_argument(
        "--steps",
        type=int,
        default=None,
        help=f"env-step budget; the learning rate anneals over it (default the preset's, else {DEFAULT_STEPS:,})",
    )
    p.add_argument(
        "--minutes",
        type=float,
        default=None,
        help="stop after this much wall time (only stops: the schedule still follows --steps)",
    )
    p.add_argument(
        "--until",
        type=int,
        default=None,
        metavar="STEPS",
        help="stop once the run has made this many env steps (only stops: the schedule still follows --steps; "
        "a probe's budget, or one session's share of a long run)",
    )
    p.add_argument(
        "--option",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="an env option, e.g. --option frame_skip=4 (JSON values)",
    )
    p.add_argument(
        "--mode",
        choices=[m["name"] for m in MODES],
        default=None,
        help="train on a ChopperScape-Bench mode's rules (docs/site/bench.md): the options it sets are set; a preset's "
        "or an --option's value that contradicts the mode is refused",
    )
    p.add_argument(
        "--preset",
        choices=sorted(PRESETS),
        default=None,
        help="recipe preset: features (the default), fast (features at frame skip 4, learning in minutes), pixels "
        "(42x42 grayscale frames alone, a CNN), pixels-large (the same with 256 envs over 28 M decisions, for "
        "--device cuda) or pixels-teacher (84x84 frames, for a features --teacher); flags override it",
    )
    defaults = Recipe()
    for f in RECIPE_FLAGS:
        value = getattr(defaults, f)
        # A boolean setting is a switch pair (--torch-compile / --no-torch-compile); any other takes a value.
        kind: dict = {"action": argparse.BooleanOptionalAction} if isinstance(value, bool) else {"type": type(value)}
        p.add_argument(
            f"--{f.replace('_', '-')}",
            **kind,
            default=None,
            help=f"default {value!r} (or the preset's)",
        )
    p.add_argument("--no-norm-obs", action="store_true")
    p.add_argument("--no-norm-reward", action="store_true")
    p.add_argument(
        "--no-invert-frames",
        action="store_true",
        help="CNN recipes: read frames as frame / 255 (chopperscape 0.1.0), not 1 - frame / 255",
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="start over in an --out folder that already holds a run (that run is first moved into OUT/replaced-N)",
    )
    return p


def _resumed(p: argparse.ArgumentParser, a: argparse.Namespace) -> Recipe:
    """The recipe `--resume DIR` continues (its `recipe.json`); exit 2 naming any flag that would change it."""
    given = [f"--{f.replace('_', '-')}" for f in RECIPE_FLAGS if getattr(a, f) is not None]
    others = {"--steps": a.steps, "--preset": a.preset, "--mode": a.mode, "--option": a.option or None}
    given += [k for k, v in others.items() if v is not None]
    given += [
        k
        for k in ("--no-norm-obs", "--no-norm-reward", "--no-invert-frames", "--force")
        if getattr(a, k[2:].replace("-", "_"))
    ]
    if a.out is not None and a.out != a.resume:
        given.append("--out")
    if given:
        p.error(f"--resume continues the run with its own recipe.json: {', '.join(given)} cannot be given with it")
    a.out = a.resume
    try:
        recipe = read_recipe(a.resume / "recipe.json")
        check_minutes(a.minutes)
        check_until(a.until)
    except ValueError as e:
        p.error(f"--resume {a.resume}: {e}")
    return recipe
