"""ChopperScape-Bench: difficulty modes, one evaluation protocol, results files and their statistics.

    python -m chopperscape.bench modes
    python -m chopperscape.bench evaluate POLICY --mode sticky-v0 --out results.json
    python -m chopperscape.bench report results/*.json --plots out/

The modes are the core's (`chopperscape.MODES`); the protocol is stated once, in :mod:`.protocol`; a results file's
schema is :mod:`.results`; :mod:`.evaluate` plays a policy under the protocol; :mod:`.report` computes mean,
median, IQM and optimality gap with stratified-bootstrap intervals (as rliable) and draws them. Light: numpy and
gymnasium only; torch, onnxruntime, stable-baselines3 or matplotlib are imported only when a policy or a plot needs
them. The leaderboard and how to add a row: `docs/site/bench.md`.
"""

from __future__ import annotations

from .protocol import PROTOCOL, check_training_seeds, mode_options

__all__ = ["PROTOCOL", "check_training_seeds", "mode_options"]
