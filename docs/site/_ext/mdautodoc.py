"""`autodoc-md`: the API reference from the installed package's docstrings, which are Markdown.

Sphinx's own autodoc hands docstrings to the reStructuredText parser, which reads this package's Markdown tables
and fences as line blocks and literal text. This directive does what autodoc does (import the object from the
installed package, take its signature with `inspect`, its docstring with `inspect.getdoc`, walk its public
members) and writes MyST Markdown: a `py:class` / `py:function` / `py:method` / `py:property` description whose
body is the docstring, parsed by MyST. Use it from a MyST page:

    ```{autodoc-md} chopperscape.ChopperScapeEnv
    :members: reset, step, render
    ```

A module gives its docstring as text. `:members:` with no value documents every public member defined on the
class itself that has a docstring; a comma-separated list documents those. A Markdown heading in a docstring
(`## Rewards`) becomes a rubric.
"""

from __future__ import annotations

import enum
import importlib
import inspect
import re
from typing import ClassVar

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective

HEADING = re.compile(r"^(#{1,6})\s+(.*)$")


def _import(dotted: str):
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for attr in parts[i:]:
            obj = getattr(obj, attr)
        return ".".join(parts[:i]), obj
    raise ImportError(f"autodoc-md: cannot import {dotted}")


def _default(value) -> str:
    if isinstance(value, enum.Enum):
        return f"{type(value).__name__}.{value.name}"
    return repr(value)


def _signature(obj, drop_first: bool) -> str:
    """The parameters without annotations (the docstrings say the types), defaults as code."""
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return "()"
    params = list(sig.parameters.values())
    if drop_first and params and params[0].name in ("self", "cls"):
        params = params[1:]
    out, star_done = [], False
    for p in params:
        if p.kind is p.KEYWORD_ONLY and not star_done:
            out.append("*")
            star_done = True
        if p.kind is p.VAR_POSITIONAL:
            out.append(f"*{p.name}")
            star_done = True
        elif p.kind is p.VAR_KEYWORD:
            out.append(f"**{p.name}")
        elif p.default is p.empty:
            out.append(p.name)
        else:
            out.append(f"{p.name}={_default(p.default)}")
    return "(" + ", ".join(out) + ")"


def _body(obj) -> list[str]:
    doc = inspect.getdoc(obj) or ""
    lines, fence = [], None
    for line in doc.splitlines():
        stripped = line.strip()
        if stripped.startswith(("```", "~~~")):
            fence = None if fence else stripped[:3]
        m = HEADING.match(line) if fence is None else None
        if m:
            lines += ["", "```{rubric} " + m.group(2).strip(), "```", ""]
        else:
            lines.append(line)
    return _doctest_blocks(lines)


def _doctest_blocks(lines: list[str]) -> list[str]:
    """`>>>` examples (a doctest block in reST) become ```python fences."""
    out, i = [], 0
    while i < len(lines):
        if lines[i].lstrip().startswith(">>>"):
            out.append("```python")
            while i < len(lines) and lines[i].strip() and lines[i].lstrip().startswith((">>>", "...")):
                out.append(lines[i].lstrip()[4:])
                i += 1
            out.append("```")
            continue
        out.append(lines[i])
        i += 1
    return out


def _own_members(cls, names: list[str] | None):
    if names is None:
        names = [n for n in cls.__dict__ if not n.startswith("_")]
    for name in names:
        if name not in cls.__dict__:
            raise AttributeError(f"autodoc-md: {cls.__qualname__} defines no member {name!r}")
        member = cls.__dict__[name]
        if isinstance(member, property):
            if member.__doc__:
                yield "property", name, member.fget
        elif isinstance(member, (staticmethod, classmethod)):
            func = member.__func__
            if func.__doc__:
                yield "staticmethod" if isinstance(member, staticmethod) else "classmethod", name, func
        elif inspect.isroutine(member) and member.__doc__:
            yield "method", name, member


class AutodocMd(SphinxDirective):
    required_arguments = 1
    option_spec: ClassVar[dict] = {
        "members": lambda arg: [] if arg is None else [a.strip() for a in arg.split(",") if a.strip()]
    }

    def run(self):
        module, obj = _import(self.arguments[0])
        name = self.arguments[0].rsplit(".", 1)[-1]
        colons = ":" * 6
        lines: list[str] = []
        if inspect.ismodule(obj):
            lines += _body(obj)
        elif inspect.isclass(obj):
            init = obj.__init__ if "__init__" in obj.__dict__ else obj
            lines += [f"{colons}{{py:class}} {name}{_signature(init, True)}", f":module: {module}", ""]
            lines += _body(obj)
            if "members" in self.options:
                wanted = self.options["members"] or None
                for kind, mname, member in _own_members(obj, wanted):
                    inner = ":" * 5
                    if kind == "property":
                        lines += ["", f"{inner}{{py:property}} {mname}", ""]
                    else:
                        opt = [f":{kind}:"] if kind in ("staticmethod", "classmethod") else []
                        lines += ["", f"{inner}{{py:method}} {mname}{_signature(member, kind == 'method')}", *opt, ""]
                    lines += _body(member) + [inner]
            lines.append(colons)
        elif callable(obj):
            lines += [f"{colons}{{py:function}} {name}{_signature(obj, False)}", f":module: {module}", ""]
            lines += _body(obj) + [colons]
        else:
            lines += [f"{colons}{{py:data}} {name}", f":module: {module}", f":value: {obj!r}", ""]
            lines += [colons]
        node = nodes.container()
        source = StringList(lines, source=f"<docstring of {self.arguments[0]}>")
        self.state.nested_parse(source, self.content_offset, node)
        return node.children


def setup(app):
    app.add_directive("autodoc-md", AutodocMd)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
