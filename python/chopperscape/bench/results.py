"""The results file of one evaluation run: its schema, its check, and its atomic write.

A results file is JSON, `"format": "chopperscape-bench/results/1"`:

    {"format": ..., "mode": {"name", "id", "options"}, "protocol": {...},
     "policy": {"kind", "source", "sha256", "recipe", "actions", "policy_seed", "train_seeds", ["name"],
                ["args"], ["files"]},
     "package": {"name": "chopperscape", "version"},
     "episodes": [{"seed", "return", "steps", "cause"}, ...],
     "summary": {"mean_return", "median_return", "std_return", "min_return", "max_return", "mean_steps", "causes",
                 "score"},
     "meta": {"created", "python", "platform"}}

A callable policy's optional `args` (its `--policy-arg`s, `{KEY: VALUE}` strings) and `files` (`[[path, sha256],
...]`: its module's source and the files its `FILES` declares; `sha256` is then the SHA-256 of their digests
concatenated in that order) say what it was given and what it read. Optional fields on how a file was made
(`meta.commit`, `meta.command`, `training`) are :mod:`.record`'s.
`meta` is the only part that differs between two evaluations of the same policy: everything else is a function of
the policy, the mode and the protocol (:func:`comparable`). A file is written whole or not at all
(:func:`write_atomic`), and read back only if every field checks (:func:`load`): a damaged file is refused with
its name, never half-used.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

from .. import modes
from . import protocol, record

FORMAT = "chopperscape-bench/results/1"
KINDS = ("builtin", "recipe", "onnx", "sb3", "callable")
CAUSES = ("bird", "fuel", "truncated")
ACTIONS = ("greedy", "sampled", "as-is")
#: The longest row name (`policy.name`, `bench evaluate --name`).
MAX_NAME = 80
#: The lowest return an episode can have: a bird on its first step (docs/SPEC.md: -10, and the episode ends).
MIN_RETURN = -10
#: The largest results file read: 1 MiB (one is about 10 KiB: 100 episodes), checked before it is read.
MAX_RESULTS_BYTES = 1 << 20


class ResultsError(ValueError):
    """A results file that does not hold what :data:`FORMAT` says; the message starts with the file's name."""


def summary(episodes: list[dict[str, Any]], mode: str) -> dict[str, Any]:
    """The summary of a run's episodes (what :func:`check` recomputes and compares)."""
    rets = sorted(int(e["return"]) for e in episodes)
    n = len(rets)
    mean = sum(rets) / n
    mid = (rets[(n - 1) // 2] + rets[n // 2]) / 2
    causes: dict[str, int] = {}
    for e in episodes:
        causes[e["cause"]] = causes.get(e["cause"], 0) + 1
    return {
        "mean_return": round(mean, 4),
        "median_return": mid,
        "std_return": round(math.sqrt(sum((r - mean) ** 2 for r in rets) / n), 4),
        "min_return": rets[0],
        "max_return": rets[-1],
        "mean_steps": round(sum(int(e["steps"]) for e in episodes) / n, 4),
        "causes": {k: causes[k] for k in sorted(causes)},
        "score": round(mean / protocol.max_return(mode), 6),
    }


def check_name(name: Any) -> str:
    """A leaderboard row's name (optional `policy.name`): 1 to 80 printable characters, no `|` (it is a table cell),
    not only spaces. `ValueError` saying what is allowed."""
    ok = isinstance(name, str) and 0 < len(name) <= MAX_NAME and name.strip() != ""
    if not (ok and name.isprintable() and "|" not in name):
        raise ResultsError(
            f"`policy.name` {name!r}: a row's name is 1 to {MAX_NAME} printable characters without '|', "
            "e.g. 'fast (PPO, 3 M decisions)'"
        )
    return name


#: The most `--policy-arg`s, and the longest value one takes.
MAX_POLICY_ARGS, MAX_POLICY_ARG = 32, 1000


def check_policy_args(args: Any) -> dict[str, str]:
    """A callable's policy arguments (`--policy-arg KEY=VALUE`, `policy.args`): at most 32, each key a Python
    identifier other than `seed` and `stochastic` (the bench's own), each value a string of at most 1000 printable
    characters. `ValueError` saying what is allowed."""
    ok = isinstance(args, dict) and len(args) <= MAX_POLICY_ARGS
    for k, v in args.items() if isinstance(args, dict) else ():
        ok = ok and isinstance(k, str) and k.isidentifier() and k not in ("seed", "stochastic")
        ok = ok and isinstance(v, str) and len(v) <= MAX_POLICY_ARG and v.isprintable()
    if not ok:
        raise ValueError(
            f"policy arguments {str(args)[:80]!r}: allowed at most {MAX_POLICY_ARGS} KEY=VALUE, each KEY an identifier "
            f"other than seed and stochastic, each VALUE at most {MAX_POLICY_ARG} printable characters"
        )
    return args


def _need(cond: bool, what: str) -> None:
    if not cond:
        raise ResultsError(what)


def _short(n: int) -> str:
    """An integer for a message: its digits, or for a long one its first digits and how many there are."""
    text = str(n)
    return text if len(text) <= 24 else f"{text[:12]}… ({len(text.lstrip('-'))} digits)"


def _int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def check(doc: Any) -> dict[str, Any]:
    """`doc` if it is a complete, consistent results document; `ResultsError` naming the first field that is not."""
    _need(isinstance(doc, dict), "not a JSON object")
    _need(doc.get("format") == FORMAT, f"`format` is {doc.get('format')!r}, not {FORMAT!r}")
    for key in ("mode", "protocol", "policy", "package", "episodes", "summary"):
        _need(key in doc, f"`{key}` is missing")
    mode = doc["mode"]
    _need(isinstance(mode, dict) and isinstance(mode.get("name"), str), "`mode.name` is missing")
    try:
        known = modes.mode(mode["name"])
    except ValueError as e:
        raise ResultsError(f"`mode.name`: {e}") from None
    _need(
        mode == {"name": known["name"], "id": known["id"], "options": known["options"]},
        f"`mode` does not match mode {known['name']!r} of this package",
    )
    _need(
        doc["protocol"] == protocol.PROTOCOL, f"`protocol` is not this package's protocol (version {protocol.VERSION})"
    )
    pol = doc["policy"]
    _need(isinstance(pol, dict) and pol.get("kind") in KINDS, f"`policy.kind` must be one of {', '.join(KINDS)}")
    _need(isinstance(pol.get("source"), str) and pol["source"] != "", "`policy.source` must be a non-empty string")
    if "name" in pol:
        check_name(pol["name"])
    sha = pol.get("sha256")
    _need(sha is None or (isinstance(sha, str) and len(sha) == 64), "`policy.sha256` must be 64 hex digits or null")
    _need(pol.get("actions") in ACTIONS, f"`policy.actions` must be one of {', '.join(ACTIONS)}")
    _need(
        pol["kind"] == "callable" or ("args" not in pol and "files" not in pol),
        "`policy.args` and `policy.files` are a callable policy's only",
    )
    if "args" in pol:
        try:
            check_policy_args(pol["args"])
        except ValueError as e:
            raise ResultsError(f"`policy.args`: {e}") from None
    files = pol.get("files")
    _need(
        files is None
        or (
            isinstance(files, list)
            and 0 < len(files) <= 1000
            and all(
                isinstance(f, list)
                and len(f) == 2
                and isinstance(f[0], str)
                and isinstance(f[1], str)
                and len(f[1]) == 64
                for f in files
            )
        ),
        "`policy.files` must be a list of [path, sha256]",
    )
    _need(_int(pol.get("policy_seed")) and pol["policy_seed"] >= 0, "`policy.policy_seed` must be an int >= 0")
    seeds = pol.get("train_seeds")
    _need(
        seeds is None or (isinstance(seeds, list) and len(seeds) == 2 and all(_int(s) for s in seeds)),
        "`policy.train_seeds` must be [first, count] or null",
    )
    if seeds is not None:
        try:
            protocol.check_training_seeds(seeds[0], seeds[1])
        except ValueError as e:
            raise ResultsError(f"`policy.train_seeds`: {e}") from None
    pkg = doc["package"]
    _need(isinstance(pkg, dict) and isinstance(pkg.get("version"), str), "`package.version` is missing")
    eps = doc["episodes"]
    _need(
        isinstance(eps, list) and len(eps) == protocol.EVAL_EPISODES,
        f"`episodes` must hold {protocol.EVAL_EPISODES} episodes",
    )
    skip = protocol.max_return(known["name"]) // protocol.MAX_EPISODE_STEPS  # the mode's frame skip
    for k, (ep, seed) in enumerate(zip(eps, protocol.eval_seeds())):
        _need(
            isinstance(ep, dict) and set(ep) == {"seed", "return", "steps", "cause"},
            f"`episodes[{k}]` must hold exactly seed, return, steps, cause",
        )
        _need(ep["seed"] == seed, f"`episodes[{k}].seed` is {ep['seed']!r}, the protocol's is {seed}")
        _need(_int(ep["return"]) and _int(ep["steps"]), f"`episodes[{k}]`: return and steps must be ints")
        _need(1 <= ep["steps"] <= protocol.MAX_EPISODE_STEPS, f"`episodes[{k}].steps` out of 1..=10000")
        _need(
            MIN_RETURN <= ep["return"] <= ep["steps"] * skip,
            f"`episodes[{k}].return` {_short(ep['return'])} is out of {MIN_RETURN}..={ep['steps'] * skip}: at most "
            f"+1 per underlying step ({ep['steps']} steps at frame skip {skip}), and -10 once for a bird",
        )
        _need(ep["cause"] in CAUSES, f"`episodes[{k}].cause` must be one of {', '.join(CAUSES)}")
        _need(
            ep["cause"] != "truncated" or ep["steps"] == protocol.MAX_EPISODE_STEPS,
            f"`episodes[{k}]` is truncated at step {ep['steps']}: the protocol truncates only at its step limit, "
            f"{protocol.MAX_EPISODE_STEPS}",
        )
    _need(doc["summary"] == summary(eps, mode["name"]), "`summary` does not match `episodes`")
    try:  # the optional fields of how the file was made (commit, command, training): .record
        record.check(doc)
    except ValueError as e:
        raise ResultsError(str(e)) from None
    return doc


def load(path: str | os.PathLike) -> dict[str, Any]:
    """Reads and checks a results file; `ResultsError` whose message is `results file NAME: what is wrong`. Only a
    regular file of at most `MAX_RESULTS_BYTES` is read (a pipe, a device or a larger file is refused before
    anything is read)."""
    from .._checks import regular_file

    name = str(path)
    try:
        regular_file(path, f"results file {name!r}", MAX_RESULTS_BYTES)
    except ValueError as e:
        raise ResultsError(str(e)) from None
    try:
        with open(path, "rb") as f:
            data = f.read(MAX_RESULTS_BYTES + 1)
        if len(data) > MAX_RESULTS_BYTES:
            raise ResultsError(f"results file {name!r} is more than the {MAX_RESULTS_BYTES:,} bytes allowed")
        text = data.decode("utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise ResultsError(f"results file {name!r}: cannot read it ({e})") from None
    try:
        doc = json.loads(text)
    except RecursionError:
        raise ResultsError(f"results file {name!r}: not JSON a results file can be (nested too deeply)") from None
    except ValueError as e:
        raise ResultsError(f"results file {name!r}: not JSON ({e})") from None
    try:
        return check(doc)
    except ResultsError as e:
        raise ResultsError(f"results file {name!r}: {e}") from None
    except (OverflowError, RecursionError, TypeError) as e:  # numbers or structures no results file holds
        raise ResultsError(f"results file {name!r}: not a results file ({type(e).__name__}: {e})") from None


def check_out(out: str | os.PathLike, *inputs: str | os.PathLike) -> None:
    """`ValueError` for an `--out` that a results file must not replace: a folder, a device (`/dev/null`), a pipe or
    a socket (replacing one would swap it for a regular file, and leave a FIFO's reader waiting), or one of the
    command's `inputs` (the policy file, by any path). Checked before any work; nothing is written."""
    import stat

    try:
        st = os.stat(out)
    except FileNotFoundError:
        return
    except OSError as e:
        raise ValueError(f"--out {str(out)!r}: cannot use it ({e.strerror or e})") from None
    if stat.S_ISDIR(st.st_mode):
        raise ValueError(f"--out {str(out)!r} is a folder: give a file name for the results file")
    if not stat.S_ISREG(st.st_mode):
        kind = "a device" if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode) else "a pipe or a socket"
        raise ValueError(
            f"--out {str(out)!r} is {kind}, not a regular file: a results file replaces a regular file only (leave "
            "--out out to print the results to standard output)"
        )
    for given in inputs:
        try:
            same = os.path.samefile(out, given)
        except OSError:
            continue
        if same:
            raise ValueError(f"--out {str(out)!r} is the input {str(given)!r}: write the results to another file")


def comparable(doc: dict[str, Any]) -> dict[str, Any]:
    """Everything but `meta`: what two evaluations of the same policy must agree on."""
    return {k: v for k, v in doc.items() if k != "meta"}


def dumps(doc: dict[str, Any]) -> str:
    """The file's text: sorted keys, two-space indent, a final newline (stable for diffs and hashes)."""
    return json.dumps(doc, indent=2, sort_keys=True) + "\n"


def write_atomic(path: str | os.PathLike, text: str) -> None:
    """Writes `text` to `path` whole or not at all: a temporary file beside it named with the process id
    (`.NAME.PID.tmp`), flushed and fsynced, then `os.replace`d over `path` (and the folder fsynced). On any error
    the temporary file is removed and `path` is left as it was."""
    target = Path(path)
    tmp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    try:
        fd = os.open(target.parent, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
