"""Deprecated: the built-in policies are `chopperscape.policies` (issue 18: one word for one concept, "policy").

This module only re-exports them, under the new names and the old ones (`Pilot` is `Policy`, `VectorPilot` is
`VectorPolicy`); importing it warns (`FutureWarning`, shown by default). It goes away in 0.3.0, with the other 0.1
paths (`chopperscape._moved`).
"""

from __future__ import annotations

import warnings

from .policies import (  # noqa: F401  (re-exported)
    NAMES,
    Policy,
    VectorPolicy,
    _check_name,
    _check_seed,
    episodes,
    fixed,
    heuristic,
    make,
    random,
)

__chopperscape_shim__ = True  # the 0.1 paths that warn (see chopperscape._moved)

#: The old names.
Pilot = Policy
VectorPilot = VectorPolicy

__all__ = [
    "NAMES",
    "Pilot",
    "Policy",
    "VectorPilot",
    "VectorPolicy",
    "episodes",
    "fixed",
    "heuristic",
    "make",
    "random",
]

# stacklevel 2: the module that imports this one (the warnings machinery skips importlib's own frames).
warnings.warn(
    "chopperscape.pilots is deprecated: use chopperscape.policies (Pilot -> Policy, VectorPilot -> VectorPolicy; "
    "it goes away in 0.3.0)",
    FutureWarning,
    stacklevel=2,
)
