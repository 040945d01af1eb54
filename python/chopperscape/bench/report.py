"""Aggregates over runs, as rliable computes them, and their pictures.

    python -m chopperscape.bench report RESULTS... [--plots DIR] [--format svg]

A row is one policy (its `source`, and its actions when sampled) on one mode; `--pool-modes` makes a row of a
policy over every mode it has runs of, the modes being its tasks. A run's score is its normalised mean return
(:mod:`.protocol`: 1.0 is the most the mode allows). A row's score matrix has one column per mode (task) and one
entry per run; the aggregates are rliable's
(Agarwal et al. 2021, `rliable.metrics`):

- mean: the mean over tasks of each task's mean over runs;
- median: the median over tasks of each task's mean over runs (with one task, that task's mean);
- IQM: the interquartile mean of all runs' scores, pooled (`scipy.stats.trim_mean(x, 0.25)`: the lowest and the
  highest `int(0.25 · n)` of the `n` scores are dropped and the rest averaged; with 10 runs, the middle 6);
- optimality gap: `γ − mean(min(score, γ))` with γ = 1;

each with a 95 % stratified-bootstrap percentile interval: runs are resampled with replacement within each task,
independently, 50,000 times (rliable's defaults), from a seeded generator, so a report is reproducible. A task of
one run (a deterministic policy: the heuristic, one trained model) has no runs to resample: its run's score is
resampled instead, as the mean of its 100 episodes drawn with replacement (a percentile bootstrap over the episodes,
the same 50,000 times), so its interval is over episodes, one run, and the table says so. rliable
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
#: Episode resamples drawn at once for a one-run task (bounds the memory of a large `--resamples`).
EPISODE_BLOCK = 10_000
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


def _resamples(
    tasks: Tasks, resamples: int, seed: int, episodes: Sequence[np.ndarray | None] | None = None
) -> list[np.ndarray]:
    """Per task, a `(resamples, runs)` array of that task's runs drawn with replacement (stratified by task). A task
    of one run whose `episodes` (its episodes' normalised returns) are given is a `(resamples, 1)` array of that
    run's score with its episodes drawn with replacement instead: the interval over episodes of a one-run task."""
    rng = np.random.default_rng(seed)
    out = []
    for i, t in enumerate(tasks):
        t = np.asarray(t, dtype=np.float64)
        ep = None if episodes is None else episodes[i]
        if ep is not None and len(t) == 1:
            ep = np.asarray(ep, dtype=np.float64)
            means = [  # in blocks: a resample of episodes holds 100 of them, not one float per run
                ep[rng.integers(0, len(ep), size=(min(EPISODE_BLOCK, resamples - k), len(ep)))].mean(axis=1)
                for k in range(0, resamples, EPISODE_BLOCK)
            ]
            out.append(np.concatenate(means)[:, None])
            continue
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
    tasks: Tasks,
    resamples: int = RESAMPLES,
    level: float = 0.95,
    seed: int = 0,
    episodes: Sequence[np.ndarray | None] | None = None,
) -> dict[str, dict[str, float]]:
    """`{metric: {"point", "low", "high"}}` for every metric of `METRICS`: the point estimate and its stratified
    percentile-bootstrap interval (over runs; over a one-run task's `episodes` where they are given)."""
    draws = _resamples(tasks, resamples, seed, episodes)
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


def _runs(docs: Sequence[dict[str, Any]], pool_modes: bool = False) -> dict[str, dict[str, list[dict[str, Any]]]]:
    """`{row: {mode: [results documents]}}`: the runs of each row (see :func:`group`)."""
    out: dict[str, dict[str, list[dict[str, Any]]]] = {}
    for d in docs:
        mode = d["mode"]["name"]
        key = _label(d) if pool_modes else f"{_label(d)} @ {mode}"
        out.setdefault(key, {}).setdefault(mode, []).append(d)
    return out


def group(docs: Sequence[dict[str, Any]], pool_modes: bool = False) -> dict[str, dict[str, list[float]]]:
    """`{row: {mode: [run scores]}}`. A row is a policy (its name or source, and its actions when sampled) on one mode;
    with `pool_modes`, a policy on every mode it has runs of (the modes are then its tasks)."""
    return {
        row: {m: [d["summary"]["score"] for d in ds] for m, ds in by_mode.items()}
        for row, by_mode in _runs(docs, pool_modes).items()
    }


def settings(doc: dict[str, Any]) -> dict[str, Any]:
    """What every run of one row must share (:func:`check_settings`): the policy's kind, its actions, the observation
    it played, and for a built-in or callable policy its source and the names of its policy arguments (a trained
    row's runs are different files, so their paths and hashes differ; a callable's arguments' values may too, as
    each training seed's weights file)."""
    pol = doc["policy"]
    out: dict[str, Any] = {"kind": pol["kind"], "actions": pol["actions"], "observation": pol.get("observation")}
    if pol["kind"] in ("builtin", "callable"):
        out["source"] = pol["source"]
    if pol["kind"] == "callable":
        out["policy arguments"] = sorted(pol.get("args") or {})
    return out


def _says(s: dict[str, Any], keys: Sequence[str]) -> str:
    return ", ".join(f"{k} {json.dumps(s.get(k), sort_keys=True)}" for k in keys)


def settings_conflict(name: str, new: dict[str, Any], new_file: str, old: dict[str, Any], old_file: str) -> str:
    """The message refusing a run of row `name` whose settings differ from another run's, both named."""
    keys = [k for k in (*old, *[k for k in new if k not in old]) if old.get(k) != new.get(k)]
    return (
        f"results file {new_file!r}: row {name!r} is already {old_file!r}'s with other settings ({_says(old, keys)}; "
        f"here {_says(new, keys)}): the runs of one row share their settings; give this run another --name"
    )


def row_key(doc: dict[str, Any]) -> str:
    """The row a run joins whatever its mode: its `policy.name` when it has one (sampled actions under that name
    are the same name, so refused with other settings), else its label."""
    return doc["policy"].get("name") or _label(doc)


def check_settings(docs: Sequence[dict[str, Any]], paths: Sequence[str] | None = None) -> None:
    """`ResultsError` for two runs of one row (:func:`row_key`) whose :func:`settings` differ, naming both files
    and both settings: a new `--name` equal to an existing row with another policy source, kind, observation or
    stochasticity is refused, never merged into it."""
    names = list(paths) if paths is not None else [f"run {i}" for i in range(len(docs))]
    first: dict[str, tuple[dict[str, Any], str]] = {}
    for d, where in zip(docs, names):
        key, s = row_key(d), settings(d)
        if key not in first:
            first[key] = (s, where)
        elif first[key][0] != s:
            raise ResultsError(settings_conflict(key, s, where, *first[key]))


#: The most results files `check_joins` reads in the `--out` folder.
MAX_JOIN_FILES = 5000


def check_joins(doc: dict[str, Any], out: str | os.PathLike) -> None:
    """`ValueError` when results file `out`'s folder holds a run of `doc`'s row (:func:`row_key`) with other
    settings (:func:`settings`), naming that file and both settings: `bench evaluate --out` into a results folder
    where the name is taken by another policy is refused before the file is written. Files that are not results
    files, and `out` itself (which is replaced), are passed over; at most `MAX_JOIN_FILES` are read."""
    target = Path(out)
    folder = target.parent
    key, mine = row_key(doc), settings(doc)
    try:
        names = sorted(p for p in folder.iterdir() if p.suffix == ".json" and p.name != target.name)
    except OSError:
        return
    for path in names[:MAX_JOIN_FILES]:
        try:
            other = load(path)
        except ResultsError:
            continue
        if row_key(other) == key and settings(other) != mine:
            raise ValueError(settings_conflict(key, mine, str(out), settings(other), str(path)))


def runs_required(docs: Sequence[dict[str, Any]]) -> int:
    """The runs the protocol (:mod:`.protocol`) asks of one row on one mode, from its runs: `protocol.RUNS` (10) for a
    stochastic policy (sampled actions, a built-in that draws from its generator, or runs that differ by policy seed:
    its policy seeds 0-9) and for a row of several policies (a recipe's training seeds: different files or policy
    arguments); 1 for one deterministic policy (the heuristic, one trained model: the same file for every seed)."""
    pols = [d["policy"] for d in docs]
    stochastic = any(
        p["actions"] == "sampled" or (p["kind"] == "builtin" and p["source"] in protocol.STOCHASTIC_BUILTINS)
        for p in pols
    )
    policies = {(p["kind"], p["source"], p.get("sha256"), json.dumps(p.get("args"), sort_keys=True)) for p in pols}
    if stochastic or len(policies) > 1 or len({p["policy_seed"] for p in pols}) > 1:
        return protocol.RUNS
    return 1


#: Why a row needs ten runs (the refusal's words).
WHY_TEN = "a stochastic policy: policy seeds 0-9; a trained row: ten training seeds"


def _mean_return(docs: Sequence[dict[str, Any]]) -> float:
    """The mean return of a mode's runs: every episode's return summed (integers, exact) over their count; the mean
    of the runs' own `summary.mean_return`, without the rounding of `summary.score` to six decimals."""
    return sum(int(e["return"]) for d in docs for e in d["episodes"]) / sum(len(d["episodes"]) for d in docs)


def report(
    docs: Sequence[dict[str, Any]], resamples: int = RESAMPLES, pool_modes: bool = False, partial: bool = False
) -> list[dict[str, Any]]:
    """One row per policy and mode (or per policy, `pool_modes`): runs per mode (and the runs the protocol asks,
    :func:`runs_required`), the mean return per mode (the mean of its runs' episodes' returns, exact), and the
    aggregates of the normalised scores with their intervals (over runs; over episodes for a mode of one run).
    A row whose runs on a mode are not the protocol's count is refused (`ResultsError` naming it), or with
    `partial` shown and marked; runs of one row with different settings are refused (:func:`check_settings`)."""
    check_settings(docs)
    rows: list[dict[str, Any]] = []
    for label, by_mode in _runs(docs, pool_modes).items():
        modes = [m["name"] for m in MODES if m["name"] in by_mode]
        need = {m: runs_required(by_mode[m]) for m in modes}
        for m in modes:
            if len(by_mode[m]) != need[m] and not partial:
                n = len(by_mode[m])
                why = "one deterministic policy" if need[m] == 1 else WHY_TEN
                raise ResultsError(
                    f"row {label!r} has {n} run{'s' * (n != 1)} on {m}, and the protocol asks {need[m]} ({why}): "
                    "add the missing runs (docs/site/bench.md), or give --partial to show it marked as partial"
                )
        tasks = [np.array([d["summary"]["score"] for d in by_mode[m]]) for m in modes]
        episodes = [
            np.array([e["return"] for e in by_mode[m][0]["episodes"]]) / protocol.max_return(m)
            if len(by_mode[m]) == 1
            else None
            for m in modes
        ]
        returns = {m: round(_mean_return(by_mode[m]), 1) for m in modes}
        rows.append(
            {
                "policy": label,
                "modes": modes,
                "runs": {m: len(by_mode[m]) for m in modes},
                "runs_required": need,
                "interval_over": {m: "episodes" if len(by_mode[m]) == 1 else "runs" for m in modes},
                "mean_return": returns,
                "aggregates": interval_estimates(tasks, resamples, episodes=episodes),
            }
        )
    order = {m["name"]: i for i, m in enumerate(MODES)}
    rows.sort(key=lambda r: ([order[m] for m in r["modes"]], -r["aggregates"]["iqm"]["point"], r["policy"]))
    return rows


def runs_cell(r: dict[str, Any], m: str) -> str:
    """A mode and its runs as the table shows them: `sticky-v0 (10)`; a one-run mode says that its interval is over
    its episodes; a partial row (`--partial`) says how many runs of how many."""
    n, need = r["runs"][m], r.get("runs_required", {}).get(m, r["runs"][m])
    if n != need:
        return f"{m} ({n} of {need} runs: partial)"
    if n == 1:
        return f"{m} (1 run: interval over its episodes)"
    return f"{m} ({n})"


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
        modes = ", ".join(runs_cell(r, m) for m in r["modes"])
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
