"""The summary of a multi-seed benchmark: each seed's held-out evaluation and training curve read and checked, the
aggregate over seeds (IQM with its 95 % bootstrap interval, :mod:`chopperscape.learn.stats`), and the files it is
written to: ``summary.json``, ``summary.md`` and ``curves.png`` (with matplotlib).

Every file is checked before anything is computed from it (:func:`read_eval`, :func:`read_curve`): one that is not a
regular UTF-8 file, lacks a field, holds a value of the wrong kind, NaN, Infinity or a number out of range, or a curve
whose steps do not increase, is refused by name (`ValueError`); ``summary.json`` is always valid JSON.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from .. import _atomic
from .._checks import regular_file
from .._cli import cannot, print_line
from . import progress
from .stats import bootstrap_ci, iqm

#: What a summary reads of each evaluation JSON.
EVAL_FIELDS = ("mean_return", "std_return", "min_return", "max_return", "mean_steps", "episodes", "seed", "causes")
#: The largest evaluation JSON read (100 episodes with `--per-episode` are 10 KB).
MAX_EVAL_BYTES = 16 << 20
#: The largest number a summary takes from a file (returns, steps): far beyond any game, far below float overflow.
MAX_NUMBER = 1e15


def _seeds(n: int, kind: str = "") -> str:
    """`1 seed`, `3 seeds` (`kind`: a word before it, such as `training `)."""
    return f"{n} {kind}seed{'' if n == 1 else 's'}"


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


def read_curve(path: Path) -> tuple[np.ndarray, np.ndarray]:
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
        f"**IQM {summary['iqm']:,.0f} [95 % CI {lo:,.0f}–{hi:,.0f}]** over {_seeds(n)}; "
        f"median {summary['median']:,.0f}, mean {summary['mean']:,.0f}, worst seed {summary['min']:,.0f}; "
        f"{summary['above_heuristic']} of {n} above the "
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
    curves = {s: read_curve(p) for s, p in runs.items()}
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
    ax.plot(grid[ok] / 1e6, mid, color="tab:blue", linewidth=2, label=f"IQM of {_seeds(len(curves))} (95 % CI band)")
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
        f"ChopperScape-v0 {title}: {_seeds(len(curves), 'training ')} "
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


def write_summary(
    out: Path,
    results: dict[int, dict[str, Any]],
    baselines: dict[str, dict[str, Any]],
    curves: dict[int, Path],
    steps: int,
    title: str,
) -> int:
    """Writes `summary.json`, `summary.md` and `curves.png` into `out` and prints the table; returns `print_line`'s
    status. Everything is computed before the first file is written, and each file is written whole (`_atomic`);
    `OSError` naming `out` if a file cannot be written."""
    summary = summarise(results, baselines, steps)
    text, table = json.dumps(summary, indent=2, allow_nan=False) + "\n", markdown(summary)
    with cannot(f"write the summary into {out}"):
        plot(out, curves, summary, title)
        _atomic.write_text(out / "summary.md", table)
        _atomic.write_text(out / "summary.json", text)
    return print_line(table)
