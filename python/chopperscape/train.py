"""Deprecated since 0.2.0: moved to :mod:`chopperscape.learn.train` (this path goes away in 0.3.0)."""

import sys

from ._moved import alias, run

__chopperscape_shim__ = True
if __name__ == "__main__":
    sys.exit(run("chopperscape.train", "chopperscape.learn.train"))
alias(__name__, "chopperscape.learn.train", "chopperscape.learn.recipe", "chopperscape.learn.model")
