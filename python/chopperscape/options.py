"""The env's option lists, as the core declares them (`_core.OPTIONS`): which options exist, which are rules and
which are observation settings. Library data below every command line: the recipe, the model file, the trainer's
guidance and the command lines' `--option` parsing (`_cli.parse_options`) all read them from here."""

from __future__ import annotations

from . import _core

#: Every option of the core (`Config::set`), as `--option` takes it, `max_episode_steps` included.
CORE_OPTIONS: tuple[str, ...] = tuple(_core.OPTION_NAMES)
#: The core's rules options (`OptionInfo::rule`): what decides the game, as opposed to how it is observed.
RULE_OPTIONS: tuple[str, ...] = tuple(o["name"] for o in _core.OPTIONS if o["rule"])
#: The core's observation settings: how the game is observed and drawn, which an action log does not record.
OBSERVATION_OPTIONS: tuple[str, ...] = tuple(o["name"] for o in _core.OPTIONS if not o["rule"])
#: Options the Python environments add to the core's (bools).
PYTHON_BOOL_OPTIONS: tuple[str, ...] = ("keep_dim",)
#: What `--option` takes by default: the options of `gymnasium.make("ChopperScape-v0", ...)`.
ENV_OPTIONS: tuple[str, ...] = CORE_OPTIONS + PYTHON_BOOL_OPTIONS
