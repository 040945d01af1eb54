"""Deprecated since 0.2.0: moved to :mod:`chopperscape.learn.export` (this path goes away in 0.3.0)."""

import sys

from ._moved import alias, run

__chopperscape_shim__ = True
if __name__ == "__main__":
    sys.exit(run("chopperscape.export", "chopperscape.learn.export"))
alias(__name__, "chopperscape.learn.export")
