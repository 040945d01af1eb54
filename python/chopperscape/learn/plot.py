"""Draws learning curves from progress CSVs (``python -m chopperscape.learn.train``, the RLlib example) into a PNG.

    python -m chopperscape.learn.plot runs/ppo/progress.csv runs/rllib/progress.csv --out docs/learning_curve.png \\
        --label "PPO recipe" --label "RLlib PPO" --hline random=600 --hline heuristic=5750

Each CSV is a progress CSV (:mod:`chopperscape.learn.progress`; the return columns are enough). The left panel plots the
mean return (last 100 episodes, with ± one std as a band) against env steps, the right one against wall-clock
minutes. With ``--frame-skip`` (one per CSV), the left panel counts game frames (env steps × frame skip), so that a
pixel run at frame skip 4 and a features run at 1 share an axis (returns are per frame either way). Needs matplotlib.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .. import _atomic
from .._cli import cannot, run_command
from .progress import read


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m chopperscape.learn.plot", description=__doc__.splitlines()[0])
    p.add_argument("csv", nargs="+", type=Path)
    p.add_argument("--out", type=Path, required=True, help="PNG to write")
    p.add_argument("--label", action="append", default=[], help="one per CSV, in order (default: the folder name)")
    p.add_argument("--hline", action="append", default=[], metavar="NAME=RETURN", help="a reference line")
    p.add_argument(
        "--frame-skip",
        action="append",
        type=int,
        default=[],
        help="one per CSV, in order: the run's frame skip; the left axis then counts game frames",
    )
    p.add_argument("--title", default="ChopperScape-v0: mean return of the last 100 episodes")
    a = p.parse_args(argv)
    if a.label and len(a.label) != len(a.csv):
        p.error(f"{len(a.label)} --label for {len(a.csv)} CSV files: give one per file or none")
    if a.frame_skip and len(a.frame_skip) != len(a.csv):
        p.error(f"{len(a.frame_skip)} --frame-skip for {len(a.csv)} CSV files: give one per file or none")
    if any(k < 1 for k in a.frame_skip):
        p.error(f"invalid --frame-skip {min(a.frame_skip)}: allowed an integer ≥ 1")
    return run_command(lambda: draw(a))


def draw(a: argparse.Namespace) -> int:
    """What `main` does with its checked flags `a`: reads every CSV, draws them into `a.out`, prints its path; 0."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise ImportError("the plot needs matplotlib: pip install matplotlib") from None
    runs = [read(path) for path in a.csv]
    labels = a.label or [path.parent.name or path.stem for path in a.csv]
    fig, (ax_steps, ax_time) = plt.subplots(1, 2, figsize=(12, 4.5), sharey=True)
    if len(runs) > 10:  # past the default cycle's 10 colours: tab20's, its 10 strong ones first
        tab20 = plt.get_cmap("tab20")
        colours = [tab20(i) for i in range(20)]
        for ax in (ax_steps, ax_time):
            ax.set_prop_cycle(color=list(colours[0::2]) + list(colours[1::2]))
    skips = a.frame_skip or [1] * len(runs)
    for run, label, skip in zip(runs, labels, skips):
        lo = [m - s for m, s in zip(run["mean_return"], run["std_return"])]
        hi = [m + s for m, s in zip(run["mean_return"], run["std_return"])]
        steps = [s * skip / 1e6 for s in run["env_steps"]]
        minutes = [w / 60 for w in run["wall_s"]]
        for ax, x in ((ax_steps, steps), (ax_time, minutes)):
            (line,) = ax.plot(x, run["mean_return"], label=label)
            ax.fill_between(x, lo, hi, color=line.get_color(), alpha=0.15 if len(runs) == 1 else 0.05, linewidth=0)
    for item in a.hline:
        name, _, value = item.partition("=")
        for ax in (ax_steps, ax_time):
            ax.axhline(float(value), linestyle="--", color="grey", linewidth=1)
        ax_time.annotate(
            name,
            (1, float(value)),
            xycoords=("axes fraction", "data"),
            xytext=(-3, 3),
            textcoords="offset points",
            ha="right",
            color="grey",
        )
    ax_steps.set_xlabel("game frames (millions; env steps × frame skip)" if a.frame_skip else "env steps (millions)")
    ax_time.set_xlabel("wall-clock minutes (2-core machine)")
    ax_steps.set_ylabel("mean return")
    ax_steps.legend(loc="upper left", fontsize="small")
    for ax in (ax_steps, ax_time):
        ax.grid(alpha=0.3)
    fig.suptitle(a.title)
    fig.tight_layout()
    try:
        with cannot(f"write {a.out}"):  # an unwritable folder, a full disk
            a.out.parent.mkdir(parents=True, exist_ok=True)
            with _atomic.replacing(a.out) as tmp:
                fig.savefig(tmp, dpi=110, format=a.out.suffix.lstrip(".").lower() or "png")
    except ValueError as err:  # a format matplotlib lacks
        raise ValueError(f"cannot write {a.out}: {err}") from None
    print(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
