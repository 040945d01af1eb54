"""The old flat import paths of the modules that moved into :mod:`chopperscape.learn` and
:mod:`chopperscape.integrations` in 0.2.0. Each still works and warns where it is imported (a `FutureWarning`,
which Python shows by default); they go away in 0.3.0. ``python -m`` on an old path says so on stderr, then runs the
new one with the same arguments.

A shim module is three lines: it marks itself (``__chopperscape_shim__``), then calls :func:`run` when it is
``__main__`` and :func:`alias` otherwise.
"""

from __future__ import annotations

import importlib
import sys
import warnings
from types import FrameType, ModuleType

#: The version without the old paths.
REMOVAL = "0.3.0"


def alias(old: str, new: str, *also: str) -> ModuleType:
    """Makes the module being imported as `old` the module `new`, so that `import old` and `from old import x` give
    `new`'s names, and warns. `also` are modules whose public names join it (0.1's `chopperscape.train` held what is
    now :mod:`.learn.recipe`, :mod:`.learn.model` and :mod:`.learn.train`)."""
    module = importlib.import_module(new)
    if also:
        merged = ModuleType(old, module.__doc__)
        for name in (*also, new):
            merged.__dict__.update(
                {k: v for k, v in vars(importlib.import_module(name)).items() if not k.startswith("__")}
            )
        module = merged
    warnings.warn(
        f"{old} moved to {new}: import it from there ({old} goes away in {REMOVAL})",
        FutureWarning,
        stacklevel=_importer_level(),
    )
    sys.modules[old] = module
    return module


def run(old: str, new: str) -> int:
    """``python -m OLD``: a note on stderr, then ``python -m NEW``'s `main` with the same arguments."""
    print(f"note: python -m {old} is now python -m {new} ({old} goes away in {REMOVAL})", file=sys.stderr)
    return int(importlib.import_module(new).main(sys.argv[1:]) or 0)


def _importer_level() -> int:
    """The `stacklevel` that points the warning at the code that imported the old path: the first frame that is
    neither this module, a shim, nor the import system. (`warnings.warn` itself skips the import system's frames
    when it counts, so they are passed over here without being counted.)"""
    frame: FrameType | None = sys._getframe(1)
    level = 1
    while frame is not None:
        internal = "importlib" in frame.f_code.co_filename and "_bootstrap" in frame.f_code.co_filename
        if not internal:
            if frame.f_globals.get("__name__") != __name__ and not frame.f_globals.get("__chopperscape_shim__"):
                return level
            level += 1
        frame = frame.f_back
    return level
