"""Deprecated: the built-in policies are `chopperscape.policies` (issue 18: one word for one concept, "policy").

This module only re-exports them, under the new names and the old ones (`Pilot` is `Policy`, `VectorPilot` is
`VectorPolicy`); importing it warns `DeprecationWarning`. It will be removed in a later release.
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

#: The old names.
Pilot = Policy
VectorPilot = VectorPolicy

__all__ = [
    "NAMES",
    "Policy",
    "VectorPolicy",
    "Pilot",
    "VectorPilot",
    "make",
    "random",
    "heuristic",
    "fixed",
    "episodes",
]

# stacklevel 2: the module that imports this one (the warnings machinery skips importlib's own frames).
warnings.warn(
    "chopperscape.pilots is deprecated: use chopperscape.policies (Pilot -> Policy, VectorPilot -> VectorPolicy)",
    DeprecationWarning,
    stacklevel=2,
)
