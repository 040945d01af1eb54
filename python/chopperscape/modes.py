"""The difficulty modes of ChopperScape-Bench as the core declares them (`chopperscape::MODES`), and the one way to
read a mode's rules: what `mode=`, the Gymnasium ids, `bench evaluate --mode` and `train --mode` all mean.

Light: the core and nothing else, so that both the bench and the learning commands can use it.
"""

from __future__ import annotations

from typing import Any

from . import _core

#: The difficulty modes (ChopperScape-Bench, `docs/site/bench.md`), easiest first, as the core declares them:
#: `name` (what `mode=` takes), `id` (its Gymnasium id), `doc`, `options` (the rules options it sets, as text;
#: every other rules option keeps its default; observation options stay free).
MODES: list[dict] = [dict(m, options=dict(m["options"])) for m in _core.MODES]


def mode(name: str) -> dict[str, Any]:
    """The mode `name` of `MODES`; `ValueError` listing the names."""
    for m in MODES:
        if m["name"] == name:
            return m
    raise ValueError(f"unknown mode {name!r}: allowed {', '.join(m['name'] for m in MODES)}")


def mode_options(name: str) -> dict[str, Any]:
    """Every rules option mode `name` fixes, typed (`{"lives": 3, "frame_skip": 4, ...}`), and `mode` itself: keyword
    options that replace whatever rules a model was trained with, and that the env checks against the mode."""
    m = mode(name)
    out: dict[str, Any] = {}
    for o in _core.OPTIONS:
        if o["rule"] and o["name"] != "max_episode_steps":
            out[o["name"]] = _core.option_value(o["name"], m["options"].get(o["name"], o["default"]))
    return {**out, "mode": name}


def with_mode(name: str, options: dict[str, Any]) -> dict[str, Any]:
    """`options` (typed keyword options) with mode `name`'s rules set: the options the mode lists are added, every
    other rules option keeps its default. `ValueError` naming each given option that contradicts the mode (the
    core's rule for `mode=`, said before anything runs), and what the mode fixes it to."""
    rules = {k: v for k, v in mode_options(name).items() if k != "mode"}
    wrong = [f"{k}={options[k]!r} (the mode's: {v!r})" for k, v in rules.items() if k in options and options[k] != v]
    if wrong:
        raise ValueError(f"options contradict mode {name!r}: {', '.join(wrong)}")
    # The options the mode lists are set (typed); every other rules option keeps its default.
    return {**options, **{k: v for k, v in rules.items() if k in mode(name)["options"]}}
