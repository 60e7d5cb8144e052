"""The slugsin reader: sections, prefix formulas, $/? buffers, diagnostics with positions."""

from __future__ import annotations

import pytest

from iterplan_compiler.diagnostics import render
from iterplan_compiler.gr1.slugsin import parse, to_prefix, variables_of, write
from iterplan_compiler.oracle.gr1_explicit import evaluate

SPEC = """# comment
[INPUT]
a
b

[OUTPUT]
c

[ENV_INIT]
! a
[SYS_TRANS]
| ! a c'
$ 3 & a b | ? 0 c ^ ? 1 b'
[SYS_LIVENESS]
c
"""


def test_sections_and_formulas():
    spec, diags = parse(SPEC, "t.slugsin")
    assert diags == []
    assert spec.inputs == ("a", "b") and spec.outputs == ("c",)
    assert len(spec.lines("ENV_INIT")) == 1
    assert len(spec.lines("SYS_TRANS")) == 2
    assert spec.lines("ENV_LIVENESS") == ()
    first = spec.lines("SYS_TRANS")[0]
    assert first.span.line == 12
    assert to_prefix(first.expr) == "| ! a c'"


def test_buffer_semantics_value_is_last_entry_and_sharing():
    spec, _ = parse(SPEC)
    e = spec.lines("SYS_TRANS")[1].expr
    # $ 3 [a&b] [(a&b)|c] [((a&b)|c) ^ b']  -> value of the last entry
    assert e.op == "xor"
    assert e.args[0].op == "or" and e.args[0].args[0] is e.args[0].args[0]
    shared = e.args[0].args[0]
    assert shared.op == "and"
    assert variables_of(e) == {("a", False), ("b", False), ("c", False), ("b", True)}
    for a in (False, True):
        for b in (False, True):
            for c in (False, True):
                for bp in (False, True):
                    want = ((a and b) or c) != bp
                    assert evaluate(e, {"a": a, "b": b, "c": c}, {"b": bp}) == want


def test_roundtrip_through_writer():
    spec, _ = parse(SPEC)
    again, diags = parse(write(spec))
    assert diags == []
    for sec in spec.sections:
        assert [to_prefix(x.expr) for x in spec.lines(sec)] == \
            [to_prefix(x.expr) for x in again.lines(sec)]


def test_nested_buffers_use_innermost():
    spec, diags = parse("[INPUT]\na\nb\n[SYS_LIVENESS]\n$ 2 a $ 2 b & ? 0 ? 0\n")
    assert diags == []
    e = spec.lines("SYS_LIVENESS")[0].expr
    assert to_prefix(e) == "& b b"


def test_deeply_nested_formula_does_not_recurse():
    depth = 20000
    text = "[INPUT]\na\n[SYS_TRANS]\n" + "! " * depth + "a\n"
    spec, diags = parse(text)
    assert diags == [] and spec is not None


@pytest.mark.parametrize(
    "body, code, line, col, needle",
    [
        ("[INPUT]\na\n[SYS_TRANS]\n& a\n", "G103", 4, 4, "operand is missing"),
        ("[INPUT]\na\n[SYS_TRANS]\n& a zz\n", "G103", 4, 5, "undeclared variable 'zz'"),
        ("[INPUT]\na\n[SYS_TRANS]\na a\n", "G103", 4, 3, "extra token"),
        ("[INPUT]\na\n[SYS_TRANS]\n$ 1 ? 3\n", "G103", 4, 5, "buffer entry 3"),
        ("[INPUT]\na\n[SYS_TRANS]\n? 0\n", "G103", 4, 1, "outside of any '$'"),
        ("[INPUT]\na\n[SYS_TRANS]\n$ x a\n", "G103", 4, 3, "positive count"),
        ("[INPUT]\na\n[BOGUS]\n", "G101", 3, 1, "unknown section"),
        ("a\n[INPUT]\nb\n", "G102", 1, 1, "before the first section"),
        ("[INPUT]\na\n[OUTPUT]\na\n", "G104", 4, 1, "declared twice"),
        ("[INPUT]\na'\n", "G104", 2, 1, "not a valid variable name"),
    ],
)
def test_diagnostics_have_positions(body, code, line, col, needle):
    spec, diags = parse(body, "bad.slugsin")
    assert spec is None
    d = next(d for d in diags if d.code == code)
    assert (d.span.line, d.span.column) == (line, col)
    assert needle in d.message
    text = render(diags, {"bad.slugsin": body})
    assert f"bad.slugsin:{line}:{col}: error[{code}]" in text
