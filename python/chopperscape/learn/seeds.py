"""Trains the recipe on several seeds and reports them as the field does: IQM with a bootstrap confidence interval.

    python -m chopperscape.learn.seeds --seeds 0-9 --steps 15000000 --out runs/seeds
    python -m chopperscape.learn.train --seeds 0-9 --steps 15000000 --out runs/seeds     # the same

Every seed ``K`` is trained into ``OUT/seed-K`` by ``python -m chopperscape.learn.train`` (any other flag, such as
``--ent-coef 0.02`` or ``--option frame_skip=4``, is passed on to it), ``--jobs`` at a time, then evaluated greedily
on the same held-out seeds (``--eval-episodes 100`` from ``--eval-seed 1000000``) into ``OUT/seed-K/eval.json``. The
``random`` and ``heuristic`` built-in policies are evaluated on those seeds too. A seed whose evaluation is
already there with
the same settings is not run again, so an interrupted runner resumes where it stopped.

It then writes:

- ``OUT/summary.json`` and ``OUT/summary.md``: per-seed held-out mean, spread and end causes; the interquartile mean
  (IQM) of the per-seed means with its 95 % bootstrap confidence interval, the median, the mean, how many seeds beat
  the heuristic and the worst seed;
- ``OUT/curves.png`` (with matplotlib): every seed's training curve, their IQM with a 95 % band, random and heuristic.

Other trainers' runs (SB3, RLlib) are summarised the same way from their files: ``--summarise DIR`` reads
``DIR/seed-K.eval.json`` (``python -m chopperscape.learn.evaluate`` output, or ``rllib_ppo.py --eval-out``) and
``DIR/seed-K.csv`` (a progress CSV with ``env_steps`` and ``mean_return``) for every ``K`` there, evaluates the
baselines on the same held-out seeds (kept in ``DIR/baseline-NAME.json``) and writes the same three files into
``DIR``; ``--title`` names the trainer in the plot. Every file is checked before anything is played or written
(:func:`read_eval`, :func:`_curve`): one that is not a regular UTF-8 file, lacks a field, holds a value of the wrong
kind, NaN, Infinity or a number out of range, or a curve whose steps do not increase, is refused by name (exit 2)
and nothing is written; ``summary.json`` is always valid JSON:

    python -m chopperscape.learn.seeds --summarise docs/curves/rllib-3seeds --steps 5000000 --title "RLlib PPO"

The statistics follow Agarwal et al. 2021 ("Deep RL at the edge of the statistical precipice", the ``rliable``
library): the IQM is the mean of the middle 50 % of runs (``scipy.stats.trim_mean(x, 0.25)``), and its interval is
the percentile bootstrap over runs. With one task, rliable's stratified bootstrap *is* this plain bootstrap over
runs; it is written here in numpy (:func:`iqm`, :func:`bootstrap_ci`) rather than pulling in rliable, whose pinned
``arch`` dependency is heavy, for the 15 lines it would save. The bootstrap's generator is seeded, so a summary is
reproducible.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from .. import _atomic
from .._checks import regular_file
from .._cli import RULE_OPTIONS, print_line
from . import progress

#: Held-out evaluation: 100 episodes from seed 1,000,000 (training seeds are small numbers).
EVAL_EPISODES, EVAL_SEED = 100, 1_000_000
#: Bootstrap resamples (rliable's default).
RESAMPLES = 50_000
#: What a summary reads of each evaluation JSON.
EVAL_FIELDS = ("mean_return", "std_return", "min_return", "max_return", "mean_steps", "episodes", "seed", "causes")


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


def iqm(x: np.ndarray, axis: int = -1) -> np.ndarray:
    """Interquartile mean along `axis`: the mean of the middle 50 % (``scipy.stats.trim_mean(x, 0.25)``).

    >>> float(iqm(np.array([0.0, 10.0, 20.0, 30.0, 1000.0, -1000.0, 40.0, 50.0])))
    25.0
    """
    x = np.sort(np.asarray(x, dtype=np.float64), axis=axis)
    n = x.shape[axis]
    cut = int(0.25 * n)
    return np.take(x, np.arange(cut, n - cut), axis=axis).mean(axis=axis)


def bootstrap_ci(
    x: np.ndarray, stat=iqm, resamples: int = RESAMPLES, level: float = 0.95, seed: int = 0
) -> tuple[float, float]:
    """Percentile bootstrap interval of `stat` over runs (the last axis of `x` is the runs; earlier axes, such as
    points of a curve, are resampled together).

    >>> lo, hi = bootstrap_ci(np.array([5000.0, 6000.0, 6500.0, 7000.0]), resamples=2000)
    >>> bool(5000 <= lo <= hi <= 7000)
    True
    """
    x = np.asarray(x, dtype=np.float64)
    n = x.shape[-1]
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, n, size=(resamples, n))
    stats = stat(x[..., idx], axis=-1)  # (..., resamples)
    lo, hi = np.percentile(stats, [50 * (1 - level), 50 * (1 + level)], axis=-1)
    return lo, hi


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


def _seed_run(seed: int, a: argparse.Namespace, forward: list[str], key: dict[str, Any]) -> dict[str, Any]:
    """Trains and evaluates one seed unless its evaluation with the same settings is already there."""
    run = a.out / f"seed-{seed}"
    done = run / "eval.json"
    if os.path.lexists(done):
        prev = read_eval(done)
        if prev.get("runner") == key:
            return prev
    run.mkdir(parents=True, exist_ok=True)
    # --force: what is in the folder is an interrupted run of this seed (a finished one has its eval.json).
    cmd = [
        sys.executable,
        "-m",
        "chopperscape.learn.train",
        "--out",
        str(run),
        "--seed",
        str(seed),
        "--steps",
        str(a.steps),
        "--force",
        *forward,
    ]
    started = time.monotonic()
    _run(f"training seed {seed}", cmd, run / "train.log")
    wall = time.monotonic() - started
    result = _evaluate(
        str(run / "model.pt"), run / ".eval-raw.json", a.eval_episodes, a.eval_seed, a.option, run / "train.log"
    )
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


#: The largest evaluation JSON read (100 episodes with `--per-episode` are 10 KB).
MAX_EVAL_BYTES = 16 << 20
#: The largest number a summary takes from a file (returns, steps): far beyond any game, far below float overflow.
MAX_NUMBER = 1e15


def _json_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a number JSON allows")


def _json_float(text: str) -> float:
    x = float(text)
    if not math.isfinite(x):
        raise ValueError(f"{text} is out of range")
    return x


def read_eval(path: Path, what: str | None = None) -> dict[str, Any]:
    """An evaluation JSON (`python -m chopperscape.learn.evaluate`'s line) read and checked: a regular UTF-8 file of
    at most `MAX_EVAL_BYTES` holding an object with every field a summary reads, of the right kind (finite numbers
    in range; no NaN or Infinity). `ValueError` naming the file (or `what`) and the first thing wrong."""
    what = what or str(path)
    regular_file(path, what, MAX_EVAL_BYTES)
    try:
        with open(path, "rb") as f:
            data = f.read(MAX_EVAL_BYTES + 1)
        if len(data) > MAX_EVAL_BYTES:
            raise ValueError(f"more than {MAX_EVAL_BYTES:,} bytes")
        doc = json.loads(data.decode("utf-8"), parse_constant=_json_constant, parse_float=_json_float)
    except OSError as e:
        raise ValueError(f"{what}: cannot be read: {e.strerror or e}") from None
    except UnicodeDecodeError:
        raise ValueError(f"{what}: not an evaluation JSON (not UTF-8 text)") from None
    except (ValueError, RecursionError) as e:
        raise ValueError(f"{what}: not an evaluation JSON ({str(e)[:200]})") from None

    def bad(field: str, expected: str) -> ValueError:
        return ValueError(f"{what}: not an evaluation JSON (`{field}` must be {expected})")

    if not isinstance(doc, dict):
        raise ValueError(f"{what}: not an evaluation JSON (an object with mean_return, episodes, ... expected)")
    missing = [k for k in EVAL_FIELDS if k not in doc]
    if missing:
        raise ValueError(f"{what}: not an evaluation JSON (no {', '.join(missing)})")
    for k in ("mean_return", "std_return", "min_return", "max_return", "mean_steps"):
        v = doc[k]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not abs(v) <= MAX_NUMBER:
            raise bad(k, f"a number of at most {MAX_NUMBER:g} in size")
    for k in ("std_return", "mean_steps"):
        if doc[k] < 0:
            raise bad(k, ">= 0")
    wall = doc.get("train_wall_s", 0)  # optional: the seed runner's own record of a training's wall time
    if isinstance(wall, bool) or not isinstance(wall, (int, float)) or not 0 <= wall <= MAX_NUMBER:
        raise bad("train_wall_s", f"a number of seconds in 0..{MAX_NUMBER:g}")
    for k, low in (("episodes", 1), ("seed", 0)):
        v = doc[k]
        if isinstance(v, bool) or not isinstance(v, int) or not low <= v < 2**63:
            raise bad(k, f"an integer in {low}..2**63")
    causes = doc["causes"]
    if not isinstance(causes, dict) or not all(
        isinstance(c, str) and isinstance(v, (int, float)) and not isinstance(v, bool) and 0 <= v <= 1
        for c, v in causes.items()
    ):
        raise bad("causes", "an object of shares in [0, 1]")
    return doc


def _curve(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """A run's training curve (env steps, mean return), checked: finite, env steps increasing; `ValueError`
    naming the file."""
    regular_file(path, str(path), progress.MAX_BYTES)
    cols = progress.read(path, ("env_steps", "mean_return"))
    x, y = np.array(cols["env_steps"]), np.array(cols["mean_return"])
    if not (np.isfinite(x).all() and np.isfinite(y).all()):
        raise ValueError(f"{path}: env_steps and mean_return must be numbers in every row that has a return")
    if (np.abs(y) > MAX_NUMBER).any() or (x < 0).any() or (x > MAX_NUMBER).any() or (np.diff(x) <= 0).any():
        raise ValueError(f"{path}: env_steps must increase from row to row (>= 0) and returns be in range")
    return x, y


def summarise(results: dict[int, dict[str, Any]], baselines: dict[str, dict[str, Any]], steps: int) -> dict[str, Any]:
    """The summary object: per-seed figures and the aggregate over seeds."""
    means = np.array([results[s]["mean_return"] for s in sorted(results)])
    heuristic = baselines["heuristic"]["mean_return"]
    lo, hi = bootstrap_ci(means)
    return {
        "steps": steps,
        "seeds": sorted(results),
        "eval": {"episodes": next(iter(results.values()))["episodes"], "seed": next(iter(results.values()))["seed"]},
        "iqm": round(float(iqm(means)), 1),
        "iqm_ci95": [round(float(lo), 1), round(float(hi), 1)],
        "median": round(float(np.median(means)), 1),
        "mean": round(float(means.mean()), 1),
        "min": round(float(means.min()), 1),
        "above_heuristic": int((means > heuristic).sum()),
        "baselines": {
            k: {"mean_return": v["mean_return"], "std_return": v["std_return"]} for k, v in baselines.items()
        },
        "per_seed": {
            str(s): {
                k: results[s][k]
                for k in (
                    "mean_return",
                    "std_return",
                    "min_return",
                    "max_return",
                    "mean_steps",
                    "causes",
                    "train_wall_s",
                )
                if k in results[s]
            }
            for s in sorted(results)
        },
    }


def markdown(summary: dict[str, Any]) -> str:
    """The summary as a markdown table (per seed) and one aggregate line."""
    lines = [
        f"Held-out evaluation: {summary['eval']['episodes']} episodes from seed {summary['eval']['seed']}, greedy; "
        f"{summary['steps']:,} env steps per training seed.",
        "",
        "| training seed | mean ± std | min | max | ended by bird / fuel / limit | training wall time |",
        "|---|---|---|---|---|---|",
    ]
    for s, r in summary["per_seed"].items():
        c = r["causes"]
        wall = f"{r['train_wall_s']:,.0f} s" if "train_wall_s" in r else "–"
        lines.append(
            f"| {s} | {r['mean_return']:,.0f} ± {r['std_return']:,.0f} | {r['min_return']:,} | {r['max_return']:,} | "
            f"{c.get('bird', 0):.0%} / {c.get('fuel', 0):.0%} / {c.get('truncated', 0):.0%} | {wall} |"
        )
    for name, b in summary["baselines"].items():
        lines.append(f"| *{name} policy* | {b['mean_return']:,.0f} ± {b['std_return']:,.0f} | | | | |")
    lo, hi = summary["iqm_ci95"]
    n = len(summary["per_seed"])
    lines += [
        "",
        f"**IQM {summary['iqm']:,.0f} [95 % CI {lo:,.0f}–{hi:,.0f}]** over {n} seeds; median {summary['median']:,.0f}, "
        f"mean {summary['mean']:,.0f}, worst seed {summary['min']:,.0f}; {summary['above_heuristic']} of {n} above the "
        f"heuristic ({summary['baselines']['heuristic']['mean_return']:,.0f}).",
        "",
    ]
    return "\n".join(lines)


def plot(out: Path, runs: dict[int, Path], summary: dict[str, Any], title: str = "PPO recipe") -> Path | None:
    """Per-seed training curves, their IQM with a 95 % bootstrap band, and the baselines; `None` without matplotlib."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("note: no matplotlib, so no curves.png (pip install matplotlib)", file=sys.stderr)
        return None
    curves = {s: _curve(p) for s, p in runs.items()}
    top = min(float(x[-1]) for x, _ in curves.values() if len(x))
    grid = np.linspace(0, top, 101)[1:]
    fig, ax = plt.subplots(figsize=(8, 4.5))
    ys = []
    for _, (x, y) in sorted(curves.items()):
        ax.plot(x / 1e6, y, color="tab:blue", alpha=0.25, linewidth=0.8)
        ys.append(np.interp(grid, x, y, left=np.nan))
    stack = np.array(ys).T  # (points, runs)
    ok = ~np.isnan(stack).any(axis=1)
    mid = iqm(stack[ok])
    lo, hi = bootstrap_ci(stack[ok], resamples=2_000)
    ax.plot(grid[ok] / 1e6, mid, color="tab:blue", linewidth=2, label=f"IQM of {len(curves)} seeds (95 % CI band)")
    ax.fill_between(grid[ok] / 1e6, lo, hi, color="tab:blue", alpha=0.2, linewidth=0)
    for name, b in summary["baselines"].items():
        ax.axhline(b["mean_return"], linestyle="--", color="grey", linewidth=1)
        ax.annotate(
            name,
            (1, b["mean_return"]),
            xycoords=("axes fraction", "data"),
            xytext=(-3, 3),
            textcoords="offset points",
            ha="right",
            color="grey",
        )
    ax.set_xlabel("env steps (millions)")
    ax.set_ylabel("mean return, last 100 training episodes")
    ax.set_title(
        f"ChopperScape-v0 {title}: {len(curves)} training seeds "
        f"(held-out IQM {summary['iqm']:,.0f} [{summary['iqm_ci95'][0]:,.0f}–{summary['iqm_ci95'][1]:,.0f}])",
        fontsize="medium",
    )
    ax.legend(loc="upper left", fontsize="small")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    path = out / "curves.png"
    try:
        with _atomic.replacing(path) as tmp:
            fig.savefig(tmp, dpi=110, format="png")
    finally:
        plt.close(fig)
    return path


def main(argv: list[str] | None = None) -> int:
    from .evaluate import MAX_EPISODES
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
        if a.seeds or a.out or forward:
            p.error("--summarise DIR takes no --seeds, --out or training flags: it reads what DIR holds")
        a.steps = DEFAULT_STEPS if a.steps is None else a.steps
        return summarise_folder(a)
    if a.seeds is None or a.out is None:
        p.error("--seeds and --out are required (or --summarise DIR)")
    if any(f == "--seed" or f.startswith("--seed=") for f in forward):
        p.error("--seed: give the training seeds with --seeds")
    if any(f == "--minutes" or f.startswith("--minutes=") for f in forward):
        p.error("--minutes: a multi-seed benchmark runs every seed to the same --steps budget")
    try:
        seeds = parse_seeds(a.seeds)
    except ValueError as err:
        p.error(str(err))
    jobs = a.jobs or max(1, min(len(seeds), os.cpu_count() or 1))
    if os.path.lexists(a.out) and not a.out.is_dir():
        p.error(f"--out {a.out} is not a folder")
    forward = forward + [x for o in a.option for x in ("--option", o)]
    # Every training flag checked here, as `train` will (exit 2 naming it), before any seed is trained.
    from . import train

    first = ["--out", str(a.out / f"seed-{seeds[0]}"), "--seed", str(seeds[0])]
    if a.steps is not None:
        first += ["--steps", str(a.steps)]
    _, recipe = train.parse([*first, "--force", *forward])
    a.steps = recipe.total_steps  # the preset's budget unless --steps
    # The baselines play the rules the seeds train on (a preset's frame skip included), as `evaluate` plays a model.
    a.rules = [f"{k}={json.dumps(v)}" for k, v in recipe.env_options.items() if k in RULE_OPTIONS]
    if recipe.teacher:
        try:
            train.load_teacher(recipe)
        except ValueError as err:
            p.error(str(err))
    # What makes two runs of a seed the same run: a stored evaluation counts only if all of it matches.
    key = {"steps": a.steps, "train_args": forward, "episodes": a.eval_episodes, "seed": a.eval_seed}
    try:
        a.out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        p.error(f"--out {a.out}: cannot make the folder: {e.strerror or e}")
    try:
        with ThreadPoolExecutor(max_workers=jobs) as pool:
            futures = {s: pool.submit(_seed_run, s, a, forward, key) for s in seeds}
            base = {name: pool.submit(_baseline, name, a) for name in ("random", "heuristic")}
            results = {s: f.result() for s, f in futures.items()}
            baselines = {name: f.result() for name, f in base.items()}
    except (RuntimeError, OSError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 1
    except ValueError as err:  # a stored evaluation that is not one
        print(f"error: {err}", file=sys.stderr)
        return 2
    curves = {s: a.out / f"seed-{s}" / "progress.csv" for s in seeds}
    return write_summary(a.out, results, baselines, curves, a.steps, a.title)


def write_summary(
    out: Path,
    results: dict[int, dict[str, Any]],
    baselines: dict[str, dict[str, Any]],
    curves: dict[int, Path],
    steps: int,
    title: str,
) -> int:
    """Writes `summary.json`, `summary.md` and `curves.png` into `out` and prints the table; 0. Everything is
    computed before the first file is written, and each file is written whole (`_atomic`); 1 with one line if a
    file cannot be written."""
    summary = summarise(results, baselines, steps)
    text, table = json.dumps(summary, indent=2, allow_nan=False) + "\n", markdown(summary)
    try:
        plot(out, curves, summary, title)
        _atomic.write_text(out / "summary.md", table)
        _atomic.write_text(out / "summary.json", text)
    except OSError as e:
        print(f"error: cannot write the summary into {out}: {e.strerror or e}", file=sys.stderr)
        return 1
    return print_line(table)


def summarise_folder(a: argparse.Namespace) -> int:
    """`--summarise DIR`: the summary of another trainer's seeds from `DIR/seed-K.eval.json` and `DIR/seed-K.csv`.
    Every file is read and checked before anything is written or played: a bad one (not a regular file, not UTF-8,
    a field missing or of the wrong kind, NaN or Infinity, a number out of range, a curve whose steps do not
    increase) is refused with its name, exit 2, and nothing is written."""
    folder: Path = a.summarise
    if not folder.is_dir():
        print(f"error: {folder} has no seed-K.eval.json to summarise (it is not a folder)", file=sys.stderr)
        return 2
    results: dict[int, dict[str, Any]] = {}
    curves: dict[int, Path] = {}
    try:
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
            _curve(curve)
            curves[s] = curve
        a.out, a.option, a.rules = folder, [], []
        for name in ("random", "heuristic"):
            if os.path.lexists(folder / f"baseline-{name}.json"):
                read_eval(folder / f"baseline-{name}.json")
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    try:
        baselines = {name: _baseline(name, a) for name in ("random", "heuristic")}
    except RuntimeError as err:
        print(f"error: {err}", file=sys.stderr)
        return 1
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    return write_summary(folder, results, baselines, curves, a.steps, a.title)


if __name__ == "__main__":
    sys.exit(main())
