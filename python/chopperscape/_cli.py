"""What the package's command lines (`python -m chopperscape.train`, `.evaluate`) share."""

from __future__ import annotations

import argparse
import json
from typing import Any


def env_options(parser: argparse.ArgumentParser, items: list[str]) -> dict[str, Any]:
    """`--option NAME=VALUE` items as env keyword options; a value is read as JSON (`4`, `[84, 84]`, `"features"`)
    and kept as text when it is not JSON. A malformed item ends the program through `parser.error`."""
    options: dict[str, Any] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            parser.error(f"--option {item!r}: expected NAME=VALUE, e.g. --option frame_skip=4")
        try:
            options[name] = json.loads(value)
        except json.JSONDecodeError:
            options[name] = value
    return options
