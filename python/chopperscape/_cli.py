"""What the package's command lines (`python -m chopperscape.learn.train`, `.evaluate`, `.datasets`, ...) share:
reading `--option NAME=VALUE` per option type, the exit status of each error (`run`), and writing the result line
to standard output."""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import sys
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from . import _core, _signals
from .options import ENV_OPTIONS, PYTHON_BOOL_OPTIONS

#: Exit statuses of every command of the package (argparse's own usage errors are 2 too).
FAILED, REFUSED = 1, 2


def option_value(name: str, text: str) -> Any:
    """The typed value of option `name` given as text: parsed by the core's own option parser (`Config::set`),
    so `--option hud=false` is the bool `False`, `obs_size=84x84` the tuple `(84, 84)`, `max_episode_steps=none`
    `None`, `lives=3` the int 3, exactly as the `chopperscape` command line reads its flags. A JSON string, list or
    null is read too (`obs_type='"features"'`, `obs_size=[84,84]`, `max_episode_steps=null`). `ValueError`
    naming the option and what it allows."""
    text = text.strip()
    try:
        doc = json.loads(text)
    except ValueError:
        doc = text
    if isinstance(doc, str):
        text = doc.strip()
    elif doc is None:
        text = "none"
    elif isinstance(doc, list) and all(isinstance(v, int) and not isinstance(v, bool) for v in doc):
        text = ",".join(str(v) for v in doc)
    if name in PYTHON_BOOL_OPTIONS:
        if text in ("true", "false"):
            return text == "true"
        raise ValueError(f"invalid value {text!r} for option `{name}`: allowed true or false")
    return _core.option_value(name, text)


def parse_options(
    items: Iterable[str], allowed: Iterable[str] = ENV_OPTIONS, refused: dict[str, str] | None = None
) -> dict[str, Any]:
    """`--option NAME=VALUE` items as keyword options, each value read by `option_value`. `allowed` are the
    names this tool takes; `refused` maps names it does not take to the reason (say what to use instead).
    `ValueError` for a malformed item, a name not allowed, a value its option does not allow, or a name twice."""
    allowed = tuple(allowed)
    refused = refused or {}
    options: dict[str, Any] = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise ValueError(f"--option {item!r}: expected NAME=VALUE, e.g. --option frame_skip=4")
        if name in refused:
            raise ValueError(f"--option {name}: {refused[name]}")
        if name not in allowed:
            raise ValueError(f"--option {name}: unknown option; allowed: {', '.join(allowed)}")
        if name in options:
            raise ValueError(f"--option {name} is given twice")
        options[name] = option_value(name, value)
    return options


def env_options(
    parser: argparse.ArgumentParser,
    items: list[str],
    allowed: Iterable[str] = ENV_OPTIONS,
    refused: dict[str, str] | None = None,
) -> dict[str, Any]:
    """`parse_options`, ending the program through `parser.error` (exit status 2) on a bad item."""
    try:
        return parse_options(items, allowed, refused)
    except ValueError as e:
        parser.error(str(e))


def run_command(command: Callable[[], int]) -> int:
    """Runs a command's work and returns its exit status: what `command` returns, or for what it raises, one line
    on standard error and the status every command of the package gives it (the one map from errors to statuses):

    - `ValueError`, `ImportError`: `error: ...`, 2 (`REFUSED`): the input is refused (a flag, a file, an option,
      a missing optional package), as argparse refuses a usage;
    - `OSError`, `RuntimeError`, `FloatingPointError`: `error: ...`, 1 (`FAILED`): the work failed (a write, a
      check, a training step);
    - `_signals.Interrupted`: its own message (`interrupted; ...`), 128 + the signal: 130, 143, 129;
      `KeyboardInterrupt` (Ctrl-C outside a guard): `interrupted`, 130.

    An `OSError` in its own words (no file name) is said without its errno (`[Errno 28]`). A command says what
    failed in its exception's message, so nothing is added to it here."""
    try:
        return command()
    except _signals.Interrupted as e:
        print(e, file=sys.stderr)
        return e.exit_code
    except KeyboardInterrupt:  # Ctrl-C where no guard defers it: one line, as a deferred signal says it
        print("interrupted", file=sys.stderr)
        return 128 + signal.SIGINT
    except (ValueError, ImportError) as e:
        print(f"error: {e}", file=sys.stderr)
        return REFUSED
    except (OSError, RuntimeError, FloatingPointError) as e:
        said = e.strerror if isinstance(e, OSError) and e.strerror and not e.filename else e
        print(f"error: {said}", file=sys.stderr)
        return FAILED


@contextlib.contextmanager
def cannot(what: str) -> Iterator[None]:
    """An `OSError` in the block as one saying what could not be done: `with cannot(f"write {path}"):` makes a full
    disk `OSError("cannot write PATH: No space left on device")`, which `run_command` turns into exit status 1."""
    try:
        yield
    except OSError as e:
        raise OSError(f"cannot {what}: {e.strerror or e}") from None


def print_line(text: str) -> int:
    """Writes `text` and a newline to standard output; returns the exit status: 0, or for a closed pipe
    (`| head -0`) 141 with nothing more said (as the `chopperscape` command line and `yes | head` end), or 1 with
    one line on standard error for any other write error (`> /dev/full`). Never a traceback: standard output is
    pointed at /dev/null afterwards, so Python's own flush at exit cannot fail either."""
    return print_chunks([text])


def print_chunks(chunks: Iterable[str]) -> int:
    """`print_line` of the text the `chunks` make together, written as they come (a long line held nowhere
    whole)."""
    try:
        for chunk in chunks:
            sys.stdout.write(chunk)
        sys.stdout.write("\n")
        sys.stdout.flush()
        return 0
    except BrokenPipeError:
        status = 141
    except OSError as e:
        print(f"error: cannot write to standard output: {e}", file=sys.stderr)
        status = 1
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):
        pass
    return status
