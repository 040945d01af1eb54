"""How steady a row is over training seeds, from its results files (the bench's protocol: 100 held-out episodes a
seed): each seed's mean return, the standard error of that mean over its episodes, the share of its episodes that
ended out of fuel; then the spread of the seed means, the part of it that the evaluation's own noise explains, and how
many seeds stalled on refuelling (more than 40 % of their episodes out of fuel).

    python docs/curves/fast-steadiness/spread.py LABEL=GLOB[,GLOB...] [LABEL=GLOB ...] [--compare A B]

Each row also gets the IQM of its seeds' normalised scores with its 95 % bootstrap interval, computed by the
leaderboard's own code (`chopperscape.bench.report.interval_estimates`), so rows of more than ten seeds compare as
the leaderboard's do.

`--compare A B` adds a permutation test (20,000 shuffles, seeded) of "A's seed means are more spread than B's" (the
ratio of their standard deviations) and of "A has more stalled seeds than B" (Fisher's exact test, one-sided)."""

from __future__ import annotations

import argparse
import glob
import json
import math
import sys

import numpy as np

from chopperscape.bench.report import interval_estimates

STALLED = 0.4


def load(patterns: str) -> list[tuple[str, float, float, float, float]]:
    """(file, mean return, its standard error, share out of fuel, normalised score) per file of the comma-separated
    globs."""
    rows = []
    for pattern in patterns.split(","):
        paths = sorted(glob.glob(pattern))
        if not paths:
            raise SystemExit(f"error: no results files match {pattern!r}")
        for path in paths:
            doc = json.loads(open(path).read())
            r = np.array([e["return"] for e in doc["episodes"]], dtype=float)
            fuel = sum(e["cause"] == "fuel" for e in doc["episodes"]) / len(r)
            se = float(r.std(ddof=1) / math.sqrt(len(r)))
            rows.append((path.rsplit("/", 1)[-1], float(r.mean()), se, fuel, float(doc["summary"]["score"])))
    return rows


def fisher_greater(a_hit: int, a_n: int, b_hit: int, b_n: int) -> float:
    """P(A's stalled count >= a_hit) under the hypergeometric law of the pooled counts (one-sided Fisher)."""
    total, hits = a_n + b_n, a_hit + b_hit
    denom = math.comb(total, a_n)
    return sum(math.comb(hits, k) * math.comb(total - hits, a_n - k) for k in range(a_hit, min(hits, a_n) + 1)) / denom


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("groups", nargs="+", metavar="LABEL=GLOB")
    p.add_argument("--compare", nargs=2, metavar=("A", "B"))
    a = p.parse_args()
    groups = {}
    for g in a.groups:
        label, _, pattern = g.partition("=")
        groups[label] = load(pattern)
    print(
        "| row | seeds | mean of seed means | sd of seed means | eval noise (rms SE) | sd beyond eval noise "
        "| stalled (>40 % fuel) | lowest | IQM [95 %] |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for label, rows in groups.items():
        m = np.array([r[1] for r in rows])
        se = math.sqrt(float(np.mean([r[2] ** 2 for r in rows])))
        sd = f"{m.std(ddof=1):,.0f}" if len(m) > 1 else "–"
        beyond = f"{math.sqrt(max(float(m.var(ddof=1)) - se**2, 0.0)):,.0f}" if len(m) > 1 else "–"
        stalled = sum(r[3] > STALLED for r in rows)
        low = min(rows, key=lambda r: r[1])
        q = interval_estimates([np.array([r[4] for r in rows])])["iqm"]
        print(
            f"| {label} | {len(rows)} | {m.mean():,.0f} | {sd} | {se:,.0f} | {beyond} "
            f"| {stalled} | {low[1]:,.0f} ({low[3]:.0%} fuel) | {q['point']:.3f} [{q['low']:.3f}, {q['high']:.3f}] |"
        )
    for label, rows in groups.items():
        print(f"{label}: " + " · ".join(f"{r[1]:,.0f} ({r[3]:.0%})" for r in rows))
    if a.compare:
        x, y = (np.array([r[1] for r in groups[k]]) for k in a.compare)
        observed = x.std(ddof=1) / y.std(ddof=1)
        rng = np.random.default_rng(0)
        both = np.concatenate([x, y])
        count = 0
        for _ in range(20_000):
            s = rng.permutation(both)
            count += s[: len(x)].std(ddof=1) / s[len(x) :].std(ddof=1) >= observed
        sx = sum(r[3] > STALLED for r in groups[a.compare[0]])
        sy = sum(r[3] > STALLED for r in groups[a.compare[1]])
        print(
            f"sd ratio {a.compare[0]}/{a.compare[1]} {observed:.2f}: permutation p = {count / 20_000:.3f}; "
            f"stalled {sx}/{len(x)} against {sy}/{len(y)}: Fisher one-sided p = "
            f"{fisher_greater(sx, len(x), sy, len(y)):.3f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
