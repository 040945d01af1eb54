"""One source for each fact: the options table of `ChopperScapeEnv`'s docstring says what the core says.

The core describes every option once (`chopperscape::OPTIONS`, here `_core.OPTIONS`): its default as text and what
it allows in words. The docstring's table is written by hand for readers; these tests hold it to the core, so a
default or a range changed in one place and not the other fails here.
"""

from __future__ import annotations

import ast
import pathlib
import re

import gymnasium as gym
import pytest

import chopperscape
from chopperscape import ChopperScapeEnv, VectorEnv, _core

CORE = {o["name"]: o for o in _core.OPTIONS}


def table_rows(doc: str) -> dict[str, list[str]]:
    """The rows of the Markdown tables in `doc` whose first cell is an option name in backticks, as
    name -> [default, allowed]. A name in two rows fails: each option has one row."""
    rows: dict[str, list[str]] = {}
    for line in doc.splitlines():
        m = re.match(r"\s*\| `(\w+)` \|(.*)\|\s*$", line)
        if not m:
            continue
        name, cells = m.group(1), [c.strip() for c in m.group(2).split("|")]
        assert name not in rows, f"option {name} has two rows in the table"
        assert len(cells) == 2, f"row of {name}: expected Default | Allowed, got {cells}"
        rows[name] = cells
    return rows


ENV_ROWS = table_rows(ChopperScapeEnv.__doc__ or "")


def literal(cell: str):
    """The Python literal a table cell writes: `"auto"`, `True`, 0.01, `(600, 800)`."""
    return ast.literal_eval(cell.strip().strip("`"))


def same_value(doc, core) -> bool:
    """`doc` (read from a table) is `core` (typed by the core's parser), with the same type: a bool is not the int
    1; an int written for a float option (`0` for 0.0) is fine."""
    if isinstance(core, bool) or isinstance(doc, bool):
        return doc is core
    if isinstance(core, float):
        return isinstance(doc, (int, float)) and doc == core
    return type(doc) is type(core) and doc == core


def range_words(allowed: str) -> list[str]:
    """The part of the core's `allowed` words a Python reader must find in the table: the integer ranges
    (`1..=1000`), the probability interval `[0, 1]`, the quoted names (`"pass"`), `True`/`False` for a bool."""
    if allowed == "true or false":
        return ["`True`", "`False`"]
    words = re.findall(r"\d+\.\.=\d+|\[0, 1\]|\"\w+\"", allowed)
    assert words, f"no range found in the core's allowed words {allowed!r}"
    return words


def mentions(cell: str, word: str) -> bool:
    """`word` stands in `cell` as a whole: `1..=1000` is not in `1..=10000`."""
    return re.search(rf"(?<!\d){re.escape(word)}(?!\d)", cell) is not None


def test_the_core_table_is_the_core_option_names():
    assert [o["name"] for o in _core.OPTIONS] == list(_core.OPTION_NAMES)
    for o in _core.OPTIONS:
        assert set(o) == {"name", "default", "allowed", "doc", "rule"}
        assert isinstance(o["rule"], bool) and all(isinstance(o[k], str) and o[k] for k in ("default", "allowed"))
    # The Python environments take every core option but max_episode_steps, which belongs to gymnasium.make (the
    # TimeLimit wrapper; ChopperScapeEnv refuses it): it is checked against the registration below instead.
    assert set(chopperscape.OPTION_NAMES) >= set(CORE) - {"max_episode_steps"}


def test_max_episode_steps_is_registered_with_the_core_default():
    core = _core.option_value("max_episode_steps", CORE["max_episode_steps"]["default"])
    assert gym.spec("ChopperScape-v0").max_episode_steps == core
    vector_default = table_rows(VectorEnv.__doc__ or "")["max_episode_steps"][0]
    assert same_value(literal(vector_default), core), vector_default


def test_every_core_option_has_one_row():
    assert set(CORE) <= set(ENV_ROWS), f"no row for {sorted(set(CORE) - set(ENV_ROWS))}"


@pytest.mark.parametrize("name", list(CORE))
def test_the_row_default_is_the_core_default(name):
    core = _core.option_value(name, CORE[name]["default"])
    doc = literal(ENV_ROWS[name][0])
    assert same_value(doc, core), f"{name}: the docstring says {doc!r}, the core {core!r}"


@pytest.mark.parametrize("name", list(CORE))
def test_the_row_allows_what_the_core_allows(name):
    cell = ENV_ROWS[name][1]
    for word in range_words(CORE[name]["allowed"]):
        assert mentions(cell, word), f"{name}: {word} (from the core's {CORE[name]['allowed']!r}) missing from {cell!r}"


def test_a_changed_default_or_range_is_noticed():
    """The checks above are not vacuous: a table with one default or one range edited fails them."""
    assert not same_value(literal("0.02"), _core.option_value("bird_prob", "0.01"))
    assert not same_value(literal("`False`"), _core.option_value("hud", "true"))
    assert not same_value(literal("1"), _core.option_value("hud", "true"))
    assert not same_value(literal("`(84, 84)`"), _core.option_value("obs_size", "600x800"))
    assert not mentions("1..=10000", "1..=1000") and not mentions("11..=1000", "1..=1000")
    assert mentions("`(H, W)`, each in 8..=4096", "8..=4096")
    with pytest.raises(AssertionError, match="two rows"):
        table_rows("| `lives` | 1 | 1..=1000 |\n| `lives` | 2 | 1..=1000 |")


# --- The one table: `options!` in crates/core/src/config.rs declares each option once; every surface derives. ---

CONFIG_RS = pathlib.Path(__file__).resolve().parents[2] / "crates" / "core" / "src" / "config.rs"
ROW = re.compile(
    r"^    (?P<name>\w+): (?P<type>[^{\n]+?) \{\n"
    r"\s+default: \"(?P<default>[^\"]*)\",\n"
    r"\s+allowed: (?P<allowed>.+?),\n"
    r"\s+doc: \"(?P<doc>(?:[^\"\\]|\\.)*)\",\n"
    r"\s+role: (?P<role>rule|observation),\n"
    r"\s+flag: (?P<flag>none|\(\"[\w-]+\", \"[^\"]+\"\)),\n"
    r"\s+page: (?P<page>true|false),\n"
    r"    \},$",
    re.M | re.S,
)
#: The Python type of each Rust type of the table, as `_core.option_value` gives it.
PY_TYPES = {"u32": int, "f64": float, "bool": bool, "(u32, u32)": tuple, "Option<u32>": (int, type(None))}


def rust_table() -> list[dict[str, str]]:
    """The rows of the `options!` table, read from the Rust source (skipped where the tree is not here)."""
    if not CONFIG_RS.is_file():
        pytest.skip("the Rust sources are not next to the tests")
    source = CONFIG_RS.read_text(encoding="utf-8")
    table = source[source.index("\noptions! {\n") :]
    table = table[: table.index("\n}\n")]
    rows = [m.groupdict() for m in ROW.finditer(table)]
    assert len(rows) == table.count(" {\n        default:"), "a row of the table is not in the expected form"
    for row in rows:
        row["doc"] = re.sub(r"\\\n\s*", "", row["doc"]).replace('\\"', '"')
    return rows


def test_core_options_are_the_rust_table():
    """`_core.OPTIONS` is the table of `options!`, row for row: name, default, doc and rule as written there."""
    rows = rust_table()
    assert [r["name"] for r in rows] == [o["name"] for o in _core.OPTIONS]
    for row, o in zip(rows, _core.OPTIONS):
        assert (row["default"], row["doc"], row["role"] == "rule") == (o["default"], o["doc"], o["rule"]), o["name"]


def test_each_option_value_has_the_tables_rust_type():
    for row in rust_table():
        value = _core.option_value(row["name"], row["default"])
        expected = PY_TYPES.get(row["type"], str)  # the enums are their names
        assert isinstance(value, expected) and (expected is bool or not isinstance(value, bool)), row["name"]


def test_the_python_lists_of_options_derive_from_the_core():
    from chopperscape import options

    rows = rust_table()
    assert options.CORE_OPTIONS == tuple(r["name"] for r in rows)
    assert options.RULE_OPTIONS == tuple(r["name"] for r in rows if r["role"] == "rule")
    assert options.OBSERVATION_OPTIONS == tuple(r["name"] for r in rows if r["role"] == "observation")
    assert set(options.ENV_OPTIONS) == set(options.CORE_OPTIONS) | set(options.PYTHON_BOOL_OPTIONS)


def test_python_keywords_reach_every_option_of_the_table():
    """Every option of the table is a keyword of the Python config (`Config::set` through `_core`), defaults
    included; `max_episode_steps` belongs to `gymnasium.make`."""
    for row in rust_table():
        if row["name"] == "max_episode_steps":
            continue
        value = _core.option_value(row["name"], row["default"])
        options = {row["name"]: value} if row["name"] == "obs_type" else {"obs_type": "features", row["name"]: value}
        env = ChopperScapeEnv(**options)
        env.close()
