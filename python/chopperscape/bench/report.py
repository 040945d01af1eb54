"""Aggregates over runs, as rliable computes them, and their pictures.

    python -m chopperscape.bench report RESULTS... [--plots DIR] [--format svg]

A row is one policy (its `source`, and its actions when sampled) on one mode; `--pool-modes` makes a row of a
policy over every mode it has runs of, the modes being its tasks. A run's score is its normalised mean return
(:mod:`.protocol`: 1.0 is the most the mode allows). A row's score matrix has one column per mode (task) and one
entry per run; the aggregates are rliable's
(Agarwal et al. 2021, `rliable.metrics`):

- mean: the mean over tasks of each task's mean over runs;
- median: the median over tasks of each task's mean over runs (with one task, that task's mean);
- IQM: the mean of the middle 50 % of all runs' scores, pooled (`scipy.stats.trim_mean(x, 0.25)`);
- optimality gap: `γ − mean(min(score, γ))` with γ = 1;

each with a 95 % stratified-bootstrap percentile interval: runs are resampled with replacement within each task,
independently, 50,000 times (rliable's defaults), from a seeded generator, so a report is reproducible. rliable
itself is not used: its release (1.2.0) does not import with the pinned numpy/pandas (its `arch` dependency
fails); the same statistics are here in numpy and tested on hand-computed values. The pictures: the interval plot
of the four aggregates, and the performance profile (the fraction of runs with a score above τ, averaged over
tasks, with a 95 % band), PNG or SVG through matplotlib's Agg backend.
"""

from __future__ import annotations

import html
import json
import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .. import MODES, _atomic
from .._cli import cannot
from ..learn.stats import iqm
from . import protocol
from .results import ResultsError, comparable, load

METRICS = ("mean", "median", "iqm", "optimality_gap")
RESAMPLES = 50_000
#: The most bootstrap resamples a report draws (`--resamples`): each takes a float per run of a row.
MAX_RESAMPLES = 1_000_000
GAMMA = 1.0
Tasks = Sequence[np.ndarray]


def aggregate_mean(tasks: Tasks) -> float:
    return float(np.mean([t.mean() for t in tasks]))


def aggregate_median(tasks: Tasks) -> float:
    return float(np.median([t.mean() for t in tasks]))


def aggregate_iqm(tasks: Tasks) -> float:
    return float(iqm(np.concatenate([np.asarray(t, dtype=np.float64) for t in tasks])))


def aggregate_optimality_gap(tasks: Tasks, gamma: float = GAMMA) -> float:
    pooled = np.concatenate([np.asarray(t, dtype=np.float64) for t in tasks])
    return float(gamma - np.minimum(pooled, gamma).mean())


AGGREGATES: dict[str, Callable[[Tasks], float]] = {
    "mean": aggregate_mean,
    "median": aggregate_median,
    "iqm": aggregate_iqm,
    "optimality_gap": aggregate_optimality_gap,
}


def _resamples(tasks: Tasks, resamples: int, seed: int) -> list[np.ndarray]:
    """Per task, a `(resamples, runs)` array of that task's runs drawn with replacement (stratified by task)."""
    rng = np.random.default_rng(seed)
    out = []
    for t in tasks:
        t = np.asarray(t, dtype=np.float64)
        out.append(t[rng.integers(0, len(t), size=(resamples, len(t)))])
    return out


def _batched(name: str, draws: list[np.ndarray]) -> np.ndarray:
    """Aggregate `name` of every resample at once (the same definitions as `AGGREGATES`, along axis 1)."""
    if name == "mean":
        return np.mean([d.mean(axis=1) for d in draws], axis=0)
    if name == "median":
        return np.median([d.mean(axis=1) for d in draws], axis=0)
    pooled = np.concatenate(draws, axis=1)
    if name == "iqm":
        return iqm(pooled, axis=1)
    return GAMMA - np.minimum(pooled, GAMMA).mean(axis=1)


def interval_estimates(
    tasks: Tasks, resamples: int = RESAMPLES, level: float = 0.95, seed: int = 0
) -> dict[str, dict[str, float]]:
    """`{metric: {"point", "low", "high"}}` for every metric of `METRICS`: the point estimate and its stratified
    percentile-bootstrap interval."""
    draws = _resamples(tasks, resamples, seed)
    out = {}
    for name in METRICS:
        stats = _batched(name, draws)
        lo, hi = np.percentile(stats, [50 * (1 - level), 50 * (1 + level)])
        out[name] = {"point": AGGREGATES[name](tasks), "low": float(lo), "high": float(hi)}
    return out


def performance_profile(tasks: Tasks, taus: np.ndarray) -> np.ndarray:
    """rliable's run-score distribution: for each τ, the fraction of runs scoring above τ, averaged over tasks."""
    return np.mean([(np.asarray(t)[:, None] > taus[None, :]).mean(axis=0) for t in tasks], axis=0)


def profile_band(
    tasks: Tasks, taus: np.ndarray, resamples: int = 2_000, level: float = 0.95, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """A stratified-bootstrap 95 % band around `performance_profile`."""
    draws = _resamples(tasks, resamples, seed)
    curves = np.mean([(d[:, :, None] > taus[None, None, :]).mean(axis=1) for d in draws], axis=0)
    lo, hi = np.percentile(curves, [50 * (1 - level), 50 * (1 + level)], axis=0)
    return lo, hi


def _label(doc: dict[str, Any]) -> str:
    """A row's label: the runs' `policy.name` where they carry one (the runs of one recipe's seeds), else the
    policy's source; sampled actions are another row."""
    pol = doc["policy"]
    what = pol.get("name", pol["source"])
    return what if pol["actions"] in ("greedy", "as-is") else f"{what} ({pol['actions']})"


def group(docs: Sequence[dict[str, Any]], pool_modes: bool = False) -> dict[str, dict[str, list[float]]]:
    """`{row: {mode: [run scores]}}`. A row is a policy (its name or source, and its actions when sampled) on one mode;
    with `pool_modes`, a policy on every mode it has runs of (the modes are then its tasks)."""
    out: dict[str, dict[str, list[float]]] = {}
    for d in docs:
        mode = d["mode"]["name"]
        key = _label(d) if pool_modes else f"{_label(d)} @ {mode}"
        out.setdefault(key, {}).setdefault(mode, []).append(d["summary"]["score"])
    return out


def report(
    docs: Sequence[dict[str, Any]], resamples: int = RESAMPLES, pool_modes: bool = False
) -> list[dict[str, Any]]:
    """One row per policy and mode (or per policy, `pool_modes`): runs per mode, the mean return per mode, and the
    aggregates of the normalised scores with their intervals."""
    rows: list[dict[str, Any]] = []
    for label, by_mode in group(docs, pool_modes).items():
        modes = [m["name"] for m in MODES if m["name"] in by_mode]
        tasks = [np.array(by_mode[m]) for m in modes]
        returns = {m: round(float(np.mean(by_mode[m])) * protocol.max_return(m), 1) for m in modes}
        rows.append(
            {
                "policy": label,
                "modes": modes,
                "runs": {m: len(by_mode[m]) for m in modes},
                "mean_return": returns,
                "aggregates": interval_estimates(tasks, resamples),
            }
        )
    order = {m["name"]: i for i, m in enumerate(MODES)}
    rows.sort(key=lambda r: ([order[m] for m in r["modes"]], -r["aggregates"]["iqm"]["point"], r["policy"]))
    return rows


def cell(text: str) -> str:
    """`text` as one Markdown table cell that the docs site (MyST) shows as that text: no line breaks or other
    control characters (each becomes a space), HTML's `&`, `<`, `>` as entities, and the characters Markdown
    reads (`\\`, `|`, `` ` ``, `*`, `_`, `[`, `]`) escaped with a backslash. Whatever field a label comes from
    (a row's name, a policy's source), it cannot end the cell, add a row or reach the page as markup."""
    text = "".join(c if c.isprintable() else " " for c in text)
    text = html.escape(text, quote=False)
    return re.sub(r"([\\|`*_\[\]])", r"\\\1", text)


def markdown(rows: list[dict[str, Any]]) -> str:
    lines = [
        "| policy | modes (runs) | mean return per mode | mean | median | IQM | optimality gap |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        cells = [f"{a['point']:.4f} [{a['low']:.4f}, {a['high']:.4f}]" for a in (r["aggregates"][m] for m in METRICS)]
        modes = ", ".join(f"{m} ({r['runs'][m]})" for m in r["modes"])
        rets = ", ".join(f"{r['mean_return'][m]:,}" for m in r["modes"])
        lines.append(f"| {cell(r['policy'])} | {modes} | {rets} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def plot(
    docs: Sequence[dict[str, Any]], rows: list[dict[str, Any]], out: Path, fmt: str = "png", pool_modes: bool = False
) -> list[Path]:
    """Writes `intervals.FMT` and `profile.FMT` into `out`; returns their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with cannot(f"make the plots folder {out}"):
        out.mkdir(parents=True, exist_ok=True)
    labels = [plot_label(r["policy"]) for r in rows]
    fig, axes = plt.subplots(1, len(METRICS), figsize=(3.2 * len(METRICS), 0.6 * len(rows) + 1.4), sharey=True)
    for ax, name in zip(axes, METRICS):
        for i, r in enumerate(rows):
            a = r["aggregates"][name]
            ax.barh(i, a["high"] - a["low"], left=a["low"], height=0.6, alpha=0.7, color=f"C{i}")
            ax.vlines(a["point"], i - 0.3, i + 0.3, color="k")
        ax.set_title(name.replace("_", " "))
        ax.set_xlim(0, 1)
        ax.set_xlabel("normalised score")
        ax.grid(axis="x", alpha=0.3)
    axes[0].set_yticks(range(len(rows)), labels)
    axes[0].invert_yaxis()
    fig.tight_layout()
    paths = [out / f"intervals.{fmt}", out / f"profile.{fmt}"]
    _save(fig, paths[0], fmt)
    plt.close(fig)
    grouped = group(docs, pool_modes)
    taus = np.linspace(0, 1, 201)
    fig, ax = plt.subplots(figsize=(6, 4))
    lines = []
    for i, r in enumerate(rows):
        tasks = [np.array(grouped[r["policy"]][m]) for m in r["modes"]]
        lo, hi = profile_band(tasks, taus)
        lines += ax.plot(taus, performance_profile(tasks, taus), color=f"C{i}")
        ax.fill_between(taus, lo, hi, color=f"C{i}", alpha=0.2)
    ax.set_xlabel("normalised score τ")
    ax.set_ylabel("fraction of runs with score > τ")
    # Handles and labels given: every row is in the legend (matplotlib leaves out labels starting with "_").
    ax.legend(lines, labels, fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    _save(fig, paths[1], fmt)
    plt.close(fig)
    return paths


def plot_label(text: str) -> str:
    """A row's label as matplotlib draws it literally: `$` escaped (no mathtext), no control characters."""
    return "".join(c if c.isprintable() else " " for c in text).replace("$", r"\$")


def _save(fig: Any, path: Path, fmt: str) -> None:
    """`fig` written to `path` whole or not at all (:mod:`chopperscape._atomic`): a full disk leaves the old
    picture; `OSError` naming the file."""
    with cannot(f"write {path}"), _atomic.replacing(path) as tmp:
        fig.savefig(tmp, format=fmt)


def _run_key(doc: dict[str, Any]) -> str:
    """What makes two results files one run: everything but `meta` and the policy seed (which a deterministic
    policy ignores: its files for every policy seed are the same run)."""
    same = comparable(doc)
    same["policy"] = {k: v for k, v in same["policy"].items() if k != "policy_seed"}
    return json.dumps(same, sort_keys=True)


def load_all(paths: Sequence[str]) -> list[dict[str, Any]]:
    """Every results file, checked (`ResultsError` naming the first bad one). A run is counted once: a file given
    twice (by any path), a copy of another, or a deterministic policy's file for another policy seed (the same
    episodes) is refused with both names."""
    docs: list[dict[str, Any]] = []
    seen: dict[str, str] = {}
    files: list[tuple[str, os.stat_result]] = []
    for p in paths:
        doc = load(p)
        st = os.stat(p)
        for other, ost in files:
            if (st.st_dev, st.st_ino) == (ost.st_dev, ost.st_ino):
                raise ResultsError(f"results file {str(p)!r} is given twice (as {other!r}): give each run once")
        files.append((str(p), st))
        key = _run_key(doc)
        if key in seen:
            raise ResultsError(
                f"results file {str(p)!r} is the same run as {seen[key]!r} (the same policy and episodes): a run "
                "counts once, and a deterministic policy's files for every policy seed are one run; give one of them"
            )
        seen[key] = str(p)
        docs.append(doc)
    return docs
