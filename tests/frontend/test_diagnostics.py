"""Diagnostics suite: each ``tests/data/diagnostics/*.lts`` file marks the expected diagnostics
on the offending line with a comment ``// error: CODE`` (or ``// warning: CODE``).

The runner loads the file (and builds every machine, so build-time errors count) and checks
that the set of (line, severity, code) of the reported diagnostics equals the marked set.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from iterplan_compiler.pipeline import load_model as load

DATA = Path(__file__).resolve().parents[1] / "data" / "diagnostics"
MARK = re.compile(r"//\s*(error|warning):\s*([A-Z]\d{4})")


def _expected(text: str) -> set[tuple[int, str, str]]:
    out = set()
    for i, line in enumerate(text.splitlines(), start=1):
        for sev, code in MARK.findall(line):
            out.add((i, sev, code))
    return out


@pytest.mark.parametrize("path", sorted(DATA.glob("*.lts")), ids=lambda p: p.name)
def test_diagnostics_file(path: Path):
    text = path.read_text(encoding="utf-8")
    model, diags = load(str(path), text)
    if model is not None:
        for name in model.names():
            _, ds = model.build_lts(name)
            diags += [d for d in ds if d not in diags]
    got = {(d.span.line, d.severity.value, d.code) for d in diags
           if d.span.file == str(path)}
    assert got == _expected(text), "\n".join(d.message for d in diags)


def _messages(name: str) -> list[tuple[int, int, str]]:
    path = DATA / name
    model, diags = load(str(path), path.read_text(encoding="utf-8"))
    if model is not None:
        for n in model.names():
            diags += [d for d in model.build_lts(n)[1] if d not in diags]
    return [(d.span.line, d.span.column, d.message) for d in diags]


def test_set_used_as_constant_says_so():
    msgs = _messages("set_as_constant.lts")
    assert [m for _, _, m in msgs] == ["'S' is a set, not a constant"] * 2


def test_failed_declarations_do_not_cascade():
    msgs = [m for _, _, m in _messages("failed_declaration_no_cascade.lts")]
    assert msgs == ["division by zero", "undefined constant 'X'"]


def test_range_errors_point_at_the_value():
    got = _messages("range_caret.lts")
    assert got == [(2, 11, "empty range R = 3..1"), (4, 14, "expected an integer, got 0.5")]


def test_expected_tokens_do_not_list_declaration_keywords():
    (_, _, inner), (_, _, top) = _messages("expected_tokens.lts")
    assert top == "syntax error: unexpected ')'; expected a new declaration"
    assert "'const'" not in inner and "'assert'" not in inner and "Name" in inner


def test_unterminated_comment_at_its_start():
    assert _messages("unterminated_comment.lts") == [
        (3, 1, "unterminated comment: this '/*' has no closing '*/'")]


def test_assert_binary_operator_hint():
    [(line, col, msg)] = _messages("assert_needs_parentheses.lts")
    assert (line, col) == (4, 14)
    assert msg.endswith("parenthesise it, `assert X = (A && B)`"), msg


def test_include_cycle_shows_the_chain():
    path = DATA / "include_loop" / "a.lts"
    model, diags = load(str(path))
    assert model is None and [d.code for d in diags] == ["E0802"]
    d = diags[0]
    chain = " includes ".join(f"'{DATA / 'include_loop' / n}'"
                              for n in ("a.lts", "b.lts", "c.lts", "a.lts"))
    assert d.message == f"include cycle: {chain}"
    assert d.span.file.endswith("c.lts") and d.span.line == 1


def test_const_with_trailing_dot_is_accepted():
    path = DATA / "const_trailing_dot.lts"
    model, diags = load(str(path))
    assert diags == [] and model is not None and model.constants["N"] == 2
    lts, ds = model.build_lts("P")
    assert ds == [] and lts is not None and set(lts.alphabet) == {"a.2", "b.3"}


def test_binary_input_is_not_a_text_file_and_fast(tmp_path):
    import random
    import time

    big = tmp_path / "big.lts"
    rnd = random.Random(7)
    big.write_bytes(bytes(rnd.getrandbits(8) for _ in range(1 << 16)) * 320)  # ~20 MB
    start = time.perf_counter()
    model, diags = load(str(big))
    elapsed = time.perf_counter() - start
    assert model is None and [d.code for d in diags] == ["E0008"] and diags[0].span.line >= 1
    assert "is not a text file" in diags[0].message
    assert elapsed < 2.0, elapsed
    # a text file that happens to contain a few odd bytes is still parsed (and located)
    odd = tmp_path / "odd.lts"
    odd.write_bytes(b"P = (a -> P).\nQ = (\x01 -> Q).\n")
    _, diags = load(str(odd))
    assert [(d.code, d.span.line) for d in diags] == [("E0002", 2)]
