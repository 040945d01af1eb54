"""RLlib's `MeanStdFilter` connector with an exact merge across env runners (:class:`SyncedMeanStdFilter`).

Why. After each training iteration RLlib gathers every runner's filter state, merges them in the local runner's
connector (`merge_states`) and broadcasts the result. In Ray 2.60 that merge reads a runner's `mean_delta_array`,
the sum of the increments of its running mean since the last sync, as if it were the mean of the new
observations. From the second iteration on, every merge pulls the mean toward zero and adds the lost mean to the
variance: after 180 iterations of one runner (3 M steps of the leaderboard's row) the filter's means are about a
fortieth of the observations' and its standard deviations several times theirs. The policy then sees features
scaled by a root mean square instead of standardised, and features with a large mean and a small spread (the
fuel gauge) lose most of their resolution (``python/tests/test_rllib_meanstd.py`` reproduces RLlib's drift).

What this filter does instead. Every runner starts an iteration from the merged state the local connector holds
(the broadcast), so a runner's new observations are exactly its state *minus* that one: their count, mean and
sum of squared deviations come out of Chan et al.'s pairwise formula, solved for the second part. The merge adds
each runner's new part to the held state by the same formula, in float64. A runner whose count is below the held
one (restarted, or never synced) counts as all new. Sampling, normalisation and clipping (at 10) are RLlib's own.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.wrappers.utils import update_mean_var_count_from_moments
from ray.rllib.connectors.env_to_module.mean_std_filter import MeanStdFilter
from ray.rllib.utils.filter import RunningStat

__all__ = ["Moments", "SyncedMeanStdFilter", "combine", "subtract"]

#: Count, mean and sum of squared deviations from the mean (Welford's `M2`) of some observations.
Moments = tuple[int, np.ndarray, np.ndarray]


def combine(a: Moments, b: Moments) -> Moments:
    """The moments of the observations of `a` and of `b` together: Gymnasium's pairwise update (Chan, Golub and
    LeVeque's, the one `chopperscape.learn.normalize.RunningMeanStd` keeps), in sums of squares."""
    (na, ma, sa), (nb, mb, sb) = a, b
    if nb == 0:
        return a
    if na == 0:
        return b
    mean, var, n = update_mean_var_count_from_moments(ma, sa / na, na, mb, sb / nb, nb)
    return n, mean, var * n


def subtract(total: Moments, part: Moments) -> Moments:
    """The moments of the observations of `total` that are not in `part` (`total` = `combine(part, rest)`), with
    the sum of squares kept at 0 or more against rounding. `(0, …)` when `total` has no more observations."""
    (n, m, s), (np_, mp, sp) = total, part
    nr = n - np_
    if nr <= 0:
        return 0, np.zeros_like(m), np.zeros_like(s)
    if np_ == 0:
        return total
    mr = (n * m - np_ * mp) / nr
    delta = mr - mp
    return nr, mr, np.maximum(s - sp - delta * delta * (np_ * nr / n), 0.0)


def _moments(state: dict[str, Any]) -> Moments:
    stat = RunningStat.from_state(state)
    return int(stat.num_pushes), np.asarray(stat.mean_array, np.float64), np.asarray(stat.sum_sq_diff_array, np.float64)


def _state(moments: Moments) -> dict[str, Any]:
    n, mean, ssd = moments
    stat = RunningStat(mean.shape)
    stat.num_pushes = int(n)
    stat.mean_array = np.array(mean, np.float64)
    stat.sum_sq_diff_array = np.array(ssd, np.float64)
    return stat.to_state()  # deltas zero: nothing reads them here


class SyncedMeanStdFilter(MeanStdFilter):
    """`MeanStdFilter` whose `merge_states` adds each runner's new observations exactly (see the module)."""

    def merge_states(self, states: list[dict[str, Any]]) -> dict[str, Any]:
        if self._filters is None:
            self._init_new_filters()
        held = MeanStdFilter._get_state_from_filters(self._filters)
        merged: dict[Any, Any] = {}
        for agent_id, agent_held in held.items():
            before = [_moments(s) for s in agent_held["running_stats"]]
            totals = list(before)
            for state in states:
                if agent_id not in state:
                    continue
                runner = [_moments(s) for s in state[agent_id]["running_stats"]]
                if len(runner) != len(before):
                    raise ValueError(
                        f"observation filter states differ in structure: {len(runner)} parts against {len(before)}"
                    )
                for i, (b, r) in enumerate(zip(before, runner)):
                    totals[i] = combine(totals[i], r if r[0] < b[0] else subtract(r, b))
            merged[agent_id] = {**agent_held, "running_stats": [_state(t) for t in totals]}
        self.set_state(merged)
        return merged
