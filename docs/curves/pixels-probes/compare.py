"""Pixel probes at equal decisions (issue 43): each run's training return (the last 100 episodes) at fixed decision
counts, and the share of episodes that ended out of fuel over the 100 k decisions before each mark.

    python docs/curves/pixels-probes/compare.py RUN.csv ... [--marks 250000,500000,750000,1000000] [--smooth 500000]

`--smooth N` gives, at each mark, the mean of the progress rows' training return over the N decisions before it in
place of the last row's (the last 100 episodes swing by a quarter from one row to the next late in a run).
"""

from __future__ import annotations

import argparse
import csv


def at(path: str, marks: list[int], smooth: int = 0) -> tuple[list[str], list[str], dict[str, str]]:
    rows = list(csv.DictReader(open(path, newline="")))
    returns, fuel = [], []
    for m in marks:
        reached = bool(rows) and int(rows[-1]["env_steps"]) >= 0.98 * m
        upto = [r for r in rows if int(r["env_steps"]) <= m and r["mean_return"]]
        window = [r for r in rows if m - 100_000 < int(r["env_steps"]) <= m and r["fuel"] and r["ended"]]
        ended = sum(int(r["ended"]) for r in window)
        share = sum(float(r["fuel"]) * int(r["ended"]) for r in window) / ended if ended else float("nan")
        # The last row before the mark, or with `smooth` every row of the N decisions before it.
        recent = [r for r in upto if int(r["env_steps"]) > m - smooth] if smooth else upto[-1:]
        mean = sum(float(r["mean_return"]) for r in recent) / len(recent) if recent else 0.0
        returns.append(f"{mean:,.0f}" if recent and reached else "–")
        fuel.append(f"{share:.2f}" if reached and ended else "–")
    return returns, fuel, rows[-1] if rows else {}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("runs", nargs="+")
    p.add_argument("--marks", default="250000,500000,750000,1000000")
    p.add_argument("--smooth", type=int, default=0, help="average the training return over N decisions before a mark")
    a = p.parse_args()
    marks = [int(m) for m in a.marks.split(",")]
    print("| run | " + " | ".join(f"{m / 1e6:g} M" for m in marks) + " | fuel share at each | reached |")
    print("|---|" + "---:|" * len(marks) + "---|---|")
    for path in a.runs:
        returns, fuel, last = at(path, marks, a.smooth)
        print(f"| `{path}` | " + " | ".join(returns) + f" | {' / '.join(fuel)} | {last.get('env_steps')} |")


if __name__ == "__main__":
    main()
