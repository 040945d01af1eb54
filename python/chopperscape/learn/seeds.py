"""Trains the recipe on several seeds and reports them as the field does: IQM with a bootstrap confidence interval.

    python -m chopperscape.learn.seeds --seeds 0-9 --steps 15000000 --out runs/seeds

Every seed ``K`` is trained into ``OUT/seed-K`` by ``python -m chopperscape.learn.train`` (any other flag, such as
``--ent-coef 0.02`` or ``--option frame_skip=4``, is passed on to it, and checked as it checks it before any seed
trains), ``--jobs`` at a time, then evaluated greedily on the same held-out seeds (``--eval-episodes 100`` from
``--eval-seed 1000000``) into ``OUT/seed-K/eval.json``. The ``random`` and ``heuristic`` built-in policies are
evaluated on those seeds too. A seed whose evaluation is already there with the same settings is not run again, so
an interrupted runner resumes where it stopped.

It then writes (:mod:`chopperscape.learn.summary`):

- ``OUT/summary.json`` and ``OUT/summary.md``: per-seed held-out mean, spread and end causes; the interquartile mean
  (IQM) of the per-seed means with its 95 % bootstrap confidence interval (:mod:`chopperscape.learn.stats`), the
  median, the mean, how many seeds beat the heuristic and the worst seed;
- ``OUT/curves.png`` (with matplotlib): every seed's training curve, their IQM with a 95 % band, random and heuristic.

``--cli PATH`` trains every seed with the Rust learner instead (``PATH train --preset P``, ``PATH`` being the
``chopperscape`` command line: docs/rust-learner.md) and evaluates its ``model.onnx`` with ``PATH demo --json`` on the
same held-out seeds (the episodes ``evaluate`` plays), summarised as ``evaluate`` summarises them; only ``--preset``
is passed on:

    python -m chopperscape.learn.seeds --cli target/release/chopperscape --preset fast --seeds 0-9 --out runs/rust

Other trainers' runs (SB3, RLlib) are summarised the same way from their files: ``--summarise DIR`` reads
``DIR/seed-K.eval.json`` (``python -m chopperscape.learn.evaluate`` output, or ``rllib_ppo.py --eval-out``) and
``DIR/seed-K.csv`` (a progress CSV with ``env_steps`` and ``mean_return``) for every ``K`` there, evaluates the
baselines on the same held-out seeds (kept in ``DIR/baseline-NAME.json``) and writes the same three files into
``DIR``; ``--title`` names the trainer in the plot. The baselines play the rules the seeds were evaluated under:
``--preset NAME`` (its frame skip, and its budget unless ``--steps``) and ``--option NAME=VALUE`` for the game's
rules only; nothing else is taken. Every file is checked before anything is played or written: a bad one is refused
by name (exit 2) and nothing is written:

    python -m chopperscape.learn.seeds --summarise docs/curves/rllib-3seeds --steps 5000000 --title "RLlib PPO"
    python -m chopperscape.learn.seeds --summarise DIR --preset pixels --title "PPO, frames alone"
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from .. import _atomic
from .._cli import run_command
from ..options import RULE_OPTIONS
from . import flags
from .summary import read_curve, read_eval, write_summary

#: Held-out evaluation: 100 episodes from seed 1,000,000 (training seeds are small numbers).
EVAL_EPISODES, EVAL_SEED = 100, 1_000_000


def parse_seeds(text: str) -> list[int]:
    """``"0-9"``, ``"0,3,5"`` or ``"1,0,2-9"`` as a list of distinct seeds in the order given (the order they are
    trained in); `ValueError` naming the item.

    >>> parse_seeds("3,1,0-2")
    [3, 1, 0, 2]
    """
    seeds: dict[int, None] = {}
    for item in text.split(","):
        lo, dash, hi = item.strip().partition("-")
        try:
            a = int(lo)
            b = int(hi) if dash else a
        except ValueError:
            raise ValueError(f"--seeds {text!r}: {item!r} is not a seed or a range (e.g. 0-9 or 0,3,5)") from None
        if a < 0 or b < a or b - a >= 1000 or b >= 2**64:
            raise ValueError(
                f"--seeds {text!r}: {item!r} must be 0 <= FIRST <= LAST with at most 1000 seeds, each < 2**64"
            )
        seeds.update(dict.fromkeys(range(a, b + 1)))
    if len(seeds) > 1000:
        raise ValueError(f"--seeds {text!r}: at most 1000 seeds")
    return list(seeds)


def check_held_out(seeds: list[int], num_envs: int, eval_seed: int, eval_episodes: int) -> None:
    """`ValueError` when a seed's training would play the held-out evaluation seeds: seed `K` trains on reset seeds
    `K … K + num_envs − 1` (`train --seed K`), which must miss `eval_seed … eval_seed + eval_episodes − 1` (as
    `bench evaluate` refuses a model that reaches its evaluation seeds)."""
    lo, hi = eval_seed, eval_seed + eval_episodes  # [lo, hi)
    for first in seeds:
        k = first
        if first < hi and lo < first + num_envs:
            raise ValueError(
                f"--seeds: seed {k} trains on reset seeds {first}..{first + num_envs - 1}, which overlap the held-out "
                f"evaluation seeds {lo}..{hi - 1} (--eval-seed {eval_seed}, --eval-episodes {eval_episodes}): train "
                "on other seeds or evaluate on others"
            )


def _run(what: str, cmd: list[str], log: Path) -> None:
    with open(log, "w") as f:
        done = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT)
    if done.returncode != 0:
        tail = log.read_text(errors="replace").strip().splitlines()[-5:]
        raise RuntimeError(f"{what} failed (exit {done.returncode}); the end of {log}:\n" + "\n".join(tail))


def _evaluate(model: str, out: Path, episodes: int, seed: int, options: list[str], log: Path) -> dict[str, Any]:
    cmd = [
        sys.executable,
        "-m",
        "chopperscape.learn.evaluate",
        model,
        "--episodes",
        str(episodes),
        "--seed",
        str(seed),
        "--per-episode",
    ]
    for o in options:
        cmd += ["--option", o]
    with _atomic.replacing(out) as tmp:
        with open(tmp, "w") as f, open(log, "a") as err:
            done = subprocess.run(cmd, stdout=f, stderr=err)
        if done.returncode != 0:
            raise RuntimeError(f"evaluating {model} failed ({done.returncode}); see {log}")
    return read_eval(out)


def _evaluate_cli(cli: str, model: Path, out: Path, episodes: int, seed: int, log: Path) -> dict[str, Any]:
    """`model` (an ONNX policy) played by the command line's `demo --json` on `episodes` held-out seeds from
    `seed` (under the rules its file records), summarised as `evaluate` summarises its episodes."""
    from .episodes import summary

    cmd = [cli, "demo", "--policy", str(model), "--episodes", str(episodes), "--seed", str(seed), "--json"]
    with open(log, "a") as err:
        done = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=err, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"evaluating {model} failed ({done.returncode}); see {log}")
    rows = [json.loads(line) for line in done.stdout.splitlines() if line.strip()]
    if len(rows) != episodes:
        raise RuntimeError(f"evaluating {model}: {len(rows)} episodes played, {episodes} asked; see {log}")
    result = {"model": str(model), "seed": seed, **summary(rows)}
    result["per_episode"] = [{k: r[k] for k in ("seed", "return", "steps", "cause")} for r in rows]
    _atomic.write_text(out, json.dumps(result, allow_nan=False))
    return read_eval(out)


def _train_command(seed: int, a: argparse.Namespace, run: Path, forward: list[str]) -> list[str]:
    """The command that trains seed `seed` into `run`: Python's trainer, or the Rust learner with `--cli`. With
    `--force`: what is in the folder is an interrupted run of this seed (a finished one has its eval.json)."""
    where = ["--out", str(run), "--seed", str(seed), "--steps", str(a.steps), "--force"]
    if a.cli:
        return [a.cli, "train", *where, *forward]
    return [sys.executable, "-m", "chopperscape.learn.train", *where, *forward]


def _seed_run(seed: int, a: argparse.Namespace, forward: list[str], key: dict[str, Any]) -> dict[str, Any]:
    """Trains and evaluates one seed unless its evaluation with the same settings is already there."""
    run = a.out / f"seed-{seed}"
    done = run / "eval.json"
    if os.path.lexists(done):
        prev = read_eval(done)
        if prev.get("runner") == key:
            return prev
    run.mkdir(parents=True, exist_ok=True)
    started = time.monotonic()
    _run(f"training seed {seed}", _train_command(seed, a, run, forward), run / "train.log")
    wall = time.monotonic() - started
    raw, log = run / ".eval-raw.json", run / "train.log"
    if a.cli:
        result = _evaluate_cli(a.cli, run / "model.onnx", raw, a.eval_episodes, a.eval_seed, log)
    else:
        result = _evaluate(str(run / "model.pt"), raw, a.eval_episodes, a.eval_seed, a.option, log)
    # The training's wall time (how long a seed takes, on whatever else shared the machine: see --jobs).
    result["train_wall_s"] = round(wall, 1)
    result["runner"] = key
    _atomic.write_text(done, json.dumps(result, allow_nan=False))
    (run / ".eval-raw.json").unlink(missing_ok=True)
    return result


def _baseline(name: str, a: argparse.Namespace) -> dict[str, Any]:
    """The built-in policy `name` on the held-out seeds, under the rules the seeds train on (`a.rules`: a preset's
    frame skip, say), so that the comparison is like for like."""
    path = a.out / f"baseline-{name}.json"
    key = {"episodes": a.eval_episodes, "seed": a.eval_seed, "option": a.rules}
    if os.path.lexists(path):
        prev = read_eval(path, f"{path} (a cached baseline: remove it to evaluate {name} again)")
        if prev.get("runner") == key:
            return prev
    result = _evaluate(
        name, a.out / f".baseline-{name}.raw", a.eval_episodes, a.eval_seed, a.rules, a.out / f"baseline-{name}.log"
    )
    result["runner"] = key
    _atomic.write_text(path, json.dumps(result, allow_nan=False))
    (a.out / f".baseline-{name}.raw").unlink(missing_ok=True)
    return result


def _options(options: list[str]) -> list[str]:
    """`--option NAME=VALUE` flags, as `train` takes them."""
    return [x for o in options for x in ("--option", o)]


def _rules(env_options: dict[str, Any]) -> list[str]:
    """What of a recipe's env options changes the game's rules (frame skip, lives, …), as `evaluate` takes them."""
    return [f"{k}={json.dumps(v)}" for k, v in env_options.items() if k in RULE_OPTIONS]


def _only_a_preset(flags: list[str]) -> bool:
    """Whether `flags` is nothing, `--preset NAME` or `--preset=NAME`: all the Rust learner takes through `--cli`."""
    return (
        flags == []
        or (len(flags) == 2 and flags[0] == "--preset")
        or (len(flags) == 1 and re.fullmatch(r"--preset=\S+", flags[0]) is not None)
    )


def main(argv: list[str] | None = None) -> int:
    from .episodes import MAX_EPISODES
    from .recipe import DEFAULT_STEPS, MAX_TOTAL_STEPS

    p = argparse.ArgumentParser(
        prog="python -m chopperscape.learn.seeds",
        description=__doc__.splitlines()[0],
        epilog="Other flags are passed on to python -m chopperscape.learn.train.",
    )
    p.add_argument("--seeds", help="training seeds, e.g. 0-9 or 0,3,5 (required unless --summarise)")
    p.add_argument("--out", type=Path, help="folder: seed-K/ per seed, summary.json, summary.md")
    p.add_argument(
        "--summarise",
        type=Path,
        metavar="DIR",
        help="train nothing: summarise DIR/seed-K.eval.json and DIR/seed-K.csv of another trainer (into DIR)",
    )
    p.add_argument("--title", default="PPO recipe", help="what trained the seeds, for the plot's title")
    p.add_argument(
        "--cli",
        metavar="PATH",
        help="train with the Rust learner: PATH is the chopperscape command line (PATH train; only --preset passed)",
    )
    p.add_argument(
        "--steps", type=int, default=None, help=f"env steps per seed (default the preset's, else {DEFAULT_STEPS:,})"
    )
    p.add_argument("--jobs", type=int, default=None, help="trainings at once (default: one per core)")
    p.add_argument("--eval-episodes", type=int, default=EVAL_EPISODES)
    p.add_argument("--eval-seed", type=int, default=EVAL_SEED)
    p.add_argument("--option", action="append", default=[], metavar="NAME=VALUE", help="env option, passed on")
    a, forward = p.parse_known_args(argv)
    if a.steps is not None and not 1 <= a.steps <= MAX_TOTAL_STEPS:
        p.error(f"--steps {a.steps}: allowed an integer in 1..={MAX_TOTAL_STEPS}")
    if not 1 <= a.eval_episodes <= MAX_EPISODES:
        p.error(f"--eval-episodes {a.eval_episodes}: allowed an integer in 1..={MAX_EPISODES}")
    if not 0 <= a.eval_seed < 2**63:
        p.error(f"--eval-seed {a.eval_seed}: allowed 0 <= seed < 2**63")
    if a.jobs is not None and not 1 <= a.jobs <= 1024:
        p.error(f"--jobs {a.jobs}: allowed an integer in 1..=1024")
    if a.summarise is not None:
        if a.seeds or a.out or a.cli or not _only_a_preset(forward):
            p.error(
                "--summarise DIR takes no --seeds, --out, --cli or training flags: it reads what DIR holds (only "
                "--preset NAME and --option NAME=VALUE, the rules its seeds were trained and evaluated under)"
            )
        # The baselines play the rules the seeds were evaluated under, as the runner plays them: a preset's frame
        # skip, say (a pixel or fast run against the heuristic at frame skip 1 would flatter neither).
        refused = sorted({o.split("=", 1)[0] for o in a.option} - set(RULE_OPTIONS))
        if refused:
            p.error(
                f"--summarise: --option {', '.join(refused)} does not change the game's rules; allowed: "
                f"{', '.join(sorted(RULE_OPTIONS))}"
            )
        _, recipe = flags.parse(["--out", str(a.summarise), "--force", *forward, *_options(a.option)])
        a.rules = _rules(recipe.env_options)
        a.steps = recipe.total_steps if a.steps is None else a.steps
        return run_command(lambda: summarise_folder(a))
    if a.seeds is None or a.out is None:
        p.error("--seeds and --out are required (or --summarise DIR)")
    if a.cli is not None:
        if not (os.path.isfile(a.cli) and os.access(a.cli, os.X_OK)):
            p.error(
                f"--cli {a.cli}: not an executable file (the chopperscape command line: target/release/chopperscape)"
            )
        passed = forward + _options(a.option)
        if not _only_a_preset(passed):
            p.error(
                f"--cli trains a preset of the Rust learner: only --preset NAME is passed on, not {' '.join(passed)}"
            )
    if any(f == "--seed" or f.startswith("--seed=") for f in forward):
        p.error("--seed: give the training seeds with --seeds")
    for stop in ("--minutes", "--until"):
        if any(f == stop or f.startswith(stop + "=") for f in forward):
            p.error(f"{stop}: a multi-seed benchmark runs every seed to the same --steps budget")
    try:
        seeds = parse_seeds(a.seeds)
    except ValueError as err:
        p.error(str(err))
    jobs = a.jobs or max(1, min(len(seeds), os.cpu_count() or 1))
    if os.path.lexists(a.out) and not a.out.is_dir():
        p.error(f"--out {a.out} is not a folder")
    forward = forward + _options(a.option)
    # Every training flag checked here, as `train` will (exit 2 naming it), before any seed is trained.
    first = ["--out", str(a.out / f"seed-{seeds[0]}"), "--seed", str(seeds[0])]
    if a.steps is not None:
        first += ["--steps", str(a.steps)]
    _, recipe = flags.parse([*first, "--force", *forward])
    a.steps = recipe.total_steps  # the preset's budget unless --steps
    try:  # seed K trains on reset seeds K .. K + num_envs - 1: never the held-out ones
        check_held_out(seeds, recipe.num_envs, a.eval_seed, a.eval_episodes)
    except ValueError as err:
        p.error(str(err))
    # The baselines play the rules the seeds train on (a preset's frame skip included), as `evaluate` plays a model.
    a.rules = _rules(recipe.env_options)
    if recipe.teacher:
        from . import guidance  # torch: only to read the teacher

        try:
            guidance.load_teacher(recipe)
        except ValueError as err:
            p.error(str(err))
    # What makes two runs of a seed the same run: a stored evaluation counts only if all of it matches.
    key = {"steps": a.steps, "train_args": forward, "episodes": a.eval_episodes, "seed": a.eval_seed}
    if a.cli:
        key["trainer"] = "rust"
    try:
        a.out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        p.error(f"--out {a.out}: cannot make the folder: {e.strerror or e}")
    return run_command(lambda: run_seeds(a, seeds, forward, key, jobs))


def run_seeds(a: argparse.Namespace, seeds: list[int], forward: list[str], key: dict[str, Any], jobs: int) -> int:
    """Trains and evaluates every seed (`jobs` at a time) and the baselines, then writes the summary; raises what
    `run_command` maps to an exit status (a training or an evaluation that failed, a stored evaluation that is not
    one)."""
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = {s: pool.submit(_seed_run, s, a, forward, key) for s in seeds}
        base = {name: pool.submit(_baseline, name, a) for name in ("random", "heuristic")}
        results = {s: f.result() for s, f in futures.items()}
        baselines = {name: f.result() for name, f in base.items()}
    curves = {s: a.out / f"seed-{s}" / "progress.csv" for s in seeds}
    return write_summary(a.out, results, baselines, curves, a.steps, a.title)


def summarise_folder(a: argparse.Namespace) -> int:
    """`--summarise DIR`: the summary of another trainer's seeds from `DIR/seed-K.eval.json` and `DIR/seed-K.csv`.
    Every file is read and checked before anything is written or played: a bad one (not a regular file, not UTF-8,
    a field missing or of the wrong kind, NaN or Infinity, a number out of range, a curve whose steps do not
    increase) is refused with its name (`ValueError`: exit 2), and nothing is written."""
    folder: Path = a.summarise
    if not folder.is_dir():
        raise ValueError(f"{folder} has no seed-K.eval.json to summarise (it is not a folder)")
    results: dict[int, dict[str, Any]] = {}
    curves: dict[int, Path] = {}
    for path in sorted(folder.glob("seed-*.eval.json")):
        name = path.name[len("seed-") : -len(".eval.json")]
        if not re.fullmatch(r"0|[1-9][0-9]{0,18}", name):
            continue
        result = read_eval(path)
        if (result["episodes"], result["seed"]) != (a.eval_episodes, a.eval_seed):
            raise ValueError(
                f"{path} played {result['episodes']} episodes from seed {result['seed']}; this summary is "
                f"of {a.eval_episodes} from {a.eval_seed} (give --eval-episodes and --eval-seed)"
            )
        results[int(name)] = result
    if not results:
        raise ValueError(f"{folder} has no seed-K.eval.json to summarise")
    for s in results:
        curve = folder / f"seed-{s}.csv"
        if not os.path.lexists(curve):
            raise ValueError(f"no training curve for every seed: {curve} missing")
        read_curve(curve)
        curves[s] = curve
    a.out = folder
    for name in ("random", "heuristic"):
        if os.path.lexists(folder / f"baseline-{name}.json"):
            read_eval(folder / f"baseline-{name}.json")
    baselines = {name: _baseline(name, a) for name in ("random", "heuristic")}
    return write_summary(folder, results, baselines, curves, a.steps, a.title)


if __name__ == "__main__":
    sys.exit(main())
