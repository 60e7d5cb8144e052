"""The structuredslugs reader: infix formulas, bounded integers, translation to slugsin IR."""

from __future__ import annotations

import itertools
import subprocess
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from iterplan_compiler.diagnostics import render
from iterplan_compiler.gr1 import slugsin, structured
from iterplan_compiler.gr1.solve import solve
from iterplan_compiler.oracle.gr1_explicit import check_strategy, evaluate, solve_explicit


def _solve(spec):
    res, diags = solve(spec)
    assert res is not None, diags
    return res


def _parse_ok(text: str):
    spec, diags = structured.parse(text, "t.structuredslugs")
    assert spec is not None, render(diags, {"t.structuredslugs": text})
    assert diags == []
    return spec


# --- Boolean-only: same game as the hand-written slugsin ------------------------------

STRUCTURED_ARBITER = """# two-client arbiter, infix
[INPUT]
r0
r1
[OUTPUT]
g0
g1
[SYS_INIT]
!g0 & !g1
[SYS_TRANS]
!(g0' & g1')
(r0' -> g0') | (r1' & !r0' -> g1')
g0' <-> (r0' & (!r1' | !g0))
g1' = (r1' & !g0')
[ENV_LIVENESS]
TRUE
[SYS_LIVENESS]
r0 -> g0
r1 -> g1 ^ FALSE
"""

SLUGSIN_ARBITER = """[INPUT]
r0
r1
[OUTPUT]
g0
g1
[SYS_INIT]
& ! g0 ! g1
[SYS_TRANS]
! & g0' g1'
| | ! r0' g0' | ! & r1' ! r0' g1'
! ^ g0' & r0' | ! r1' ! g0
! ^ g1' & r1' ! g0'
[ENV_LIVENESS]
1
[SYS_LIVENESS]
| ! r0 g0
| ! r1 ^ g1 0
"""


def test_boolean_spec_matches_slugsin_formulation():
    a = _parse_ok(STRUCTURED_ARBITER)
    b, diags = slugsin.parse(SLUGSIN_ARBITER)
    assert b is not None and diags == []
    assert a.inputs == b.inputs and a.outputs == b.outputs
    # Same truth tables line by line (all 256 valuations of x, y, x', y').
    names = a.inputs + a.outputs
    for sec in slugsin.FORMULA_SECTIONS:
        assert len(a.lines(sec)) == len(b.lines(sec)), sec
        for la, lb in zip(a.lines(sec), b.lines(sec), strict=True):
            for bits in itertools.product((False, True), repeat=2 * len(names)):
                cur = dict(zip(names, bits[:len(names)], strict=True))
                nxt = dict(zip(names, bits[len(names):], strict=True))
                assert evaluate(la.expr, cur, nxt) == evaluate(lb.expr, cur, nxt), sec
    ra, rb = _solve(a), _solve(b)
    assert ra.realizable == rb.realizable
    assert ra.realizable == solve_explicit(a)[0]
    assert ra.game.bdd.count(ra.winning, nvars=2 * len(names)) == \
        rb.game.bdd.count(rb.winning, nvars=2 * len(names))
    assert len(ra.winning) == len(rb.winning)


def _same_lines(a, b):
    names = a.inputs + a.outputs
    for sec in slugsin.FORMULA_SECTIONS:
        assert len(a.lines(sec)) == len(b.lines(sec)), sec
        for la, lb in zip(a.lines(sec), b.lines(sec), strict=True):
            for bits in itertools.product((False, True), repeat=2 * len(names)):
                cur = dict(zip(names, bits[:len(names)], strict=True))
                nxt = dict(zip(names, bits[len(names):], strict=True))
                assert evaluate(la.expr, cur, nxt) == evaluate(lb.expr, cur, nxt), sec


def test_prefix_lines_pass_through_like_slugs():
    """slugs' structured compiler accepts lines already in slugsin prefix notation (G112
    before): a pure-prefix file reads as the same spec as with the slugsin reader, and a
    file may mix both notations line by line."""
    a = _parse_ok(SLUGSIN_ARBITER)
    b, _ = slugsin.parse(SLUGSIN_ARBITER)
    _same_lines(a, b)
    both = _parse_ok("[INPUT]\nr\nx: 0...3\n[OUTPUT]\ng\n[SYS_TRANS]\n| ! r g'\n"
                     "r -> g'\n& x@0 ! x@1'\nx = 1 & x' != 2\n")
    rows = both.lines("SYS_TRANS")[-4:]
    cur = {"r": True, "g": False, "x@0": True, "x@1": False}
    nxt = {"r": False, "g": True, "x@0": False, "x@1": False}
    assert [evaluate(ln.expr, cur, nxt) for ln in rows] == [True, True, True, True]
    nxt["g"], nxt["x@1"] = False, True  # g' false, x' = 2
    assert [evaluate(ln.expr, cur, nxt) for ln in rows] == [False, False, False, False]


@pytest.mark.parametrize("line", ["& a", "& a b", "a b"])
def test_malformed_prefix_line_is_still_an_error(line):
    spec, diags = structured.parse(f"[INPUT]\na\n[SYS_TRANS]\n{line}\n", "p.structuredslugs")
    assert spec is None and diags[0].code in ("G112", "G113")


# --- integers ----------------------------------------------------------------------------


def _tracking(out_range: str, relation: str) -> str:
    return f"""[INPUT]
x: 0...2
[OUTPUT]
y: {out_range}
[SYS_TRANS]
y' {relation} x'
"""


@pytest.mark.parametrize(
    ("out_range", "relation", "want"),
    [
        ("0...2", "=", True),
        ("0...2", ">=", True),  # needs the env's range constraint: x' = 3 is no legal move
        ("0...2", ">", False),  # x' = 2 leaves y' no value (y' = 3 is out of range)
        ("0...3", ">", True),
        ("1...3", "<", False),
        ("-2...0", "!=", True),
        ("5...5", "<=", False),
        ("5...5", ">", True),
    ],
)
def test_integer_comparisons_known_verdicts(out_range, relation, want):
    spec = _parse_ok(_tracking(out_range, relation))
    res = _solve(spec)
    assert res.realizable is want
    assert solve_explicit(spec)[0] is want
    if want:
        assert check_strategy(spec, res.strategy) == []


COUNTER = """[OUTPUT]
c: 0...3
[SYS_INIT]
c = 0
[SYS_TRANS]
{step}
[SYS_LIVENESS]
c = 3
"""


@pytest.mark.parametrize(
    ("step", "want"),
    [
        ("c' = c + 1 | (c = 3 & c' = 0)", True),
        ("c' - 1 = c | c' + 3 = c", True),
        ("c' = c", False),
        ("c' = c + 2 | c' + 2 = c", False),  # only even values reachable from 0
    ],
)
def test_arithmetic_counter(step, want):
    spec = _parse_ok(COUNTER.format(step=step))
    assert _solve(spec).realizable is want
    assert solve_explicit(spec)[0] is want


def test_range_constraint_goes_to_declaring_player():
    spec = _parse_ok("[INPUT]\nx: 0...2\n[OUTPUT]\ny: 1...4\nz: 0...3\n")
    assert spec.inputs == ("x@0", "x@1") and spec.outputs == ("y@0", "y@1", "z@0", "z@1")
    assert len(spec.lines("ENV_INIT")) == 1 and len(spec.lines("ENV_TRANS")) == 1
    # y has 4 values in 2 bits and z fills its bits: no constraint for the system.
    assert spec.lines("SYS_INIT") == () and spec.lines("SYS_TRANS") == ()
    init, trans = spec.lines("ENV_INIT")[0].expr, spec.lines("ENV_TRANS")[0].expr
    for k in range(4):
        bits = {"x@0": bool(k & 1), "x@1": bool(k & 2)}
        assert evaluate(init, bits, {}) is (k <= 2)
        assert evaluate(trans, {}, bits) is (k <= 2)


_OPS = {"=": int.__eq__, "!=": int.__ne__, "<": int.__lt__, "<=": int.__le__,
        ">": int.__gt__, ">=": int.__ge__}


@settings(max_examples=60, deadline=None)
@given(lo=st.integers(-4, 4), width=st.integers(0, 6), c=st.integers(-6, 12),
       d=st.integers(-3, 3), op=st.sampled_from(sorted(_OPS)))
def test_comparison_semantics_match_integers(lo, width, c, d, op):
    hi = lo + width
    spec = _parse_ok(f"[INPUT]\nx: {lo}...{hi}\n[SYS_TRANS]\nx' + {d} {op} {c}\n"
                     if d >= 0 else
                     f"[INPUT]\nx: {lo}...{hi}\n[SYS_TRANS]\nx' - {-d} {op} {c}\n")
    expr = spec.lines("SYS_TRANS")[0].expr
    for v in range(lo, hi + 1):
        k = v - lo
        nxt = {b: bool((k >> i) & 1) for i, b in enumerate(spec.inputs)}
        assert evaluate(expr, {}, nxt) is _OPS[op](v + d, c), (v, op, c, d)


# --- bad input ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "code", "line", "col"),
    [
        ("[INPUT]\na\n[SYS_TRANS]\na & 3\n", "G113", 4, 5),
        ("[INPUT]\na\n[SYS_TRANS]\na & b\n", "G113", 4, 5),
        ("[INPUT]\na\n[SYS_TRANS]\n(a | a\n", "G112", 4, 7),
        ("[INPUT]\na\n[SYS_TRANS]\na & $\n", "G112", 4, 5),
        ("[INPUT]\nx: 0...3\n[SYS_TRANS]\n0 < x < 3\n", "G112", 4, 7),
        ("[INPUT]\nx: 0...3\n[SYS_TRANS]\nx' + 1\n", "G113", 4, 1),
        ("[INPUT]\nx: 3...1\n", "G111", 2, 1),
        ("[INPUT]\nx: 0..3\n", "G111", 2, 1),
        ("[INPUT]\na\n[OUTPUT]\na\n", "G111", 4, 1),
        ("[INPUTS]\na\n", "G110", 1, 1),
        ("a\n[INPUT]\n", "G110", 1, 1),
        ("[INPUT]\nx: 0...100000\n", "G114", 2, 1),
    ],
)
def test_bad_input_diagnostics(text, code, line, col):
    spec, diags = structured.parse(text, "bad.structuredslugs")
    assert spec is None
    assert diags and diags[0].code == code
    assert (diags[0].span.line, diags[0].span.column) == (line, col)
    assert f"bad.structuredslugs:{line}:{col}:" in render(diags, {"bad.structuredslugs": text})


def test_deep_nesting_is_a_diagnostic_not_a_crash():
    text = "[INPUT]\na\n[SYS_TRANS]\n" + "(" * 5000 + "a" + ")" * 5000 + "\n"
    spec, diags = structured.parse(text)
    assert spec is None and diags[0].code == "G112"


# --- CLI -----------------------------------------------------------------------------------


def _iterc(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "iterplan_compiler.cli", "solve", *args],
                          capture_output=True, text=True, timeout=60)


def test_cli_solves_structuredslugs(tmp_path):
    good = tmp_path / "count.structuredslugs"
    good.write_text(COUNTER.format(step="c' = c + 1 | (c = 3 & c' = 0)"))
    p = _iterc(str(good))
    assert p.returncode == 0, p.stderr
    assert p.stdout.startswith("REALIZABLE")
    other = tmp_path / "count.txt"
    other.write_text(COUNTER.format(step="c' = c"))
    p = _iterc("--format", "structuredslugs", str(other))
    assert p.returncode == 1 and p.stdout.startswith("UNREALIZABLE")
    bad = tmp_path / "bad.structuredslugs"
    bad.write_text("[OUTPUT]\nc: 0...3\n[SYS_TRANS]\nc' = = 1\n")
    p = _iterc(str(bad))
    assert p.returncode == 1
    assert "Traceback" not in p.stderr
    assert "bad.structuredslugs:4:6: error[G112]" in p.stderr
