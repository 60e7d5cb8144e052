"""The on-disk cache of parsed files (frontend/syntax_cache.py): a hit gives exactly the
syntax tree (spans included) and diagnostics of a fresh parse, without importing Lark; the
key covers the text, the path and the limits; files with errors are not stored."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from pathlib import Path

import pytest

from iterplan_compiler import limits
from iterplan_compiler.frontend import parse, syntax_cache

SPEC = """
const N = 2
range R = 0..N
fluent F = <a, b>
P = (a -> b -> P | c[i:R] -> P).
ltl_property S = [](F -> X !a)
||C = (P).
"""


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    return tmp_path / "iterplan" / "syntax"


def _spans(node: object, out: list[object]) -> list[object]:
    """Every span of the tree, in order (spans do not take part in ``==``)."""
    if isinstance(node, (tuple, list)):
        for x in node:
            _spans(x, out)
    elif hasattr(node, "__dataclass_fields__"):
        for name in node.__dataclass_fields__:
            value = getattr(node, name)
            if name == "span":
                out.append(value)
            else:
                _spans(value, out)
    return out


def test_hit_equals_fresh_parse(cache, monkeypatch):
    fresh, fresh_diags = parse.parse_text(SPEC, "t.lts")
    stored, _ = syntax_cache.parse_text(SPEC, "t.lts")
    assert len(list(cache.glob("*.pickle"))) == 1
    monkeypatch.setattr(parse, "parse_text",
                        lambda *a, **k: pytest.fail("parsed despite a cache hit"))
    hit, hit_diags = syntax_cache.parse_text(SPEC, "t.lts")
    assert hit == fresh == stored and len(hit.decls) == 6
    assert _spans(hit, []) == _spans(fresh, [])
    assert any(s.line == 5 for s in _spans(hit, []))
    assert hit_diags == fresh_diags


def test_key_covers_text_path_and_limits(cache):
    key = syntax_cache.cache_key(SPEC, "t.lts", False)
    assert key == syntax_cache.cache_key(SPEC, "t.lts", False)
    assert key != syntax_cache.cache_key(SPEC + " ", "t.lts", False)
    assert key != syntax_cache.cache_key(SPEC, "u.lts", False)
    assert key != syntax_cache.cache_key(SPEC, "t.lts", True)
    assert syntax_cache.parse_text(SPEC, "t.lts")[1] == []   # stored under the defaults
    previous = limits.set_limits(limits.Limits(max_declarations=1))
    try:
        assert key != syntax_cache.cache_key(SPEC, "t.lts", False)
        # and the limit's diagnostic is not read from an entry stored under other limits
        assert [d.code for d in syntax_cache.parse_text(SPEC, "t.lts")[1]] == ["E0006"]
    finally:
        limits.set_limits(previous)


def test_errors_are_not_stored_and_bad_entries_are_misses(cache):
    bad = "P = (a -> ."
    spec, diags = syntax_cache.parse_text(bad, "t.lts")
    assert any(d.is_error for d in diags)
    assert not list(cache.glob("*.pickle"))
    syntax_cache.parse_text(SPEC, "t.lts")
    (entry,) = cache.glob("*.pickle")
    entry.write_bytes(b"not a pickle")
    assert syntax_cache.load(syntax_cache.cache_key(SPEC, "t.lts", False)) is None
    other = syntax_cache.cache_key(SPEC + "\n", "t.lts", False)
    entry.write_bytes(pickle.dumps((other, *syntax_cache.parse_text(SPEC, "v.lts"))))
    assert syntax_cache.load(syntax_cache.cache_key(SPEC, "t.lts", False)) is None


def test_no_cache_env_disables_it(cache, monkeypatch):
    monkeypatch.setenv("ITERPLAN_NO_CACHE", "1")
    syntax_cache.parse_text(SPEC, "t.lts")
    assert not cache.exists()


def test_a_warm_compile_imports_neither_lark_nor_the_fltl_translator(tmp_path):
    """Issue #12: with the caches filled, ``iterc compile`` parses nothing and translates no
    formula, so it does not load Lark or fltl's tableau (progression/emptiness)."""
    spec = Path(__file__).resolve().parents[2] / "examples" / "fire_patrol.lts"
    code = ("import sys\n"
            "from iterplan_compiler import pipeline\n"
            f"out = pipeline.compile_spec({str(spec)!r})\n"
            "assert out.text is not None, out.diagnostics\n"
            "print(*(m in sys.modules for m in ('lark', 'iterplan_compiler.fltl.progression',"
            " 'iterplan_compiler.fltl.emptiness')))\n")
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path)}
    runs = [subprocess.run([sys.executable, "-c", code], env=env, check=True,
                           capture_output=True, text=True).stdout.split() for _ in range(2)]
    assert runs == [["True"] * 3, ["False"] * 3]
