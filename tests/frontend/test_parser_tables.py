"""The parse tables shipped with the grammar (grammar/fsp-tables.pickle, frontend/parse.py
SEED): current for the grammar, used only when they match, and the parser they load parses
exactly like one built from the grammar (syntax trees, spans, diagnostics)."""

from __future__ import annotations

import importlib.resources
from pathlib import Path

import lark
import pytest
from lark import Lark

from iterplan_compiler.frontend import parse

ROOT = Path(__file__).resolve().parents[2]


def _seed_header() -> bytes:
    seed = importlib.resources.files("iterplan_compiler.grammar").joinpath(parse.SEED)
    with seed.open("rb") as f:
        return f.readline()


def test_shipped_tables_are_current() -> None:
    header = _seed_header()
    made_for = header.split()[1:]
    here = parse.seed_header(parse._grammar_text())
    if made_for != here.split()[1:]:
        pytest.skip(f"the shipped tables are for {made_for!r}, this is lark "
                    f"{lark.__version__}: Lark builds the tables here")
    assert header == here, ("grammar/fsp.lark changed: regenerate the tables with "
                            "python -c \"from iterplan_compiler.frontend.parse import "
                            "write_seed; write_seed()\"")


def _spans(node: object, out: list[object]) -> list[object]:
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


def _parse_all(monkeypatch: pytest.MonkeyPatch, parser: Lark) -> list[object]:
    monkeypatch.setattr(parse, "parser", lambda: parser)
    for memo in (parse._decl_start_states_cached, parse._declaration_keywords):
        memo.cache_clear()
    out: list[object] = []
    files = sorted(ROOT.glob("examples/*.lts")) + sorted(ROOT.glob("stdlib/*.lts"))
    assert len(files) > 8
    for path in files:
        good = path.read_text(encoding="utf-8")
        for text in (good, good + "\nBad = (a -> ).\nWorse = (b -> @).\n"):  # errors too
            spec, diags = parse.parse_text(text, str(path))
            out.append((repr(spec), _spans(spec, []), [(d.code, d.message, d.span)
                                                       for d in diags]))
    return out


def test_seeded_parser_parses_like_a_built_one(monkeypatch: pytest.MonkeyPatch) -> None:
    text = parse._grammar_text()
    seeded = parse._from_seed(text)
    if seeded is None:
        pytest.skip("the shipped tables do not match this Lark/Python")
    built = Lark(text, cache=False, **parse._OPTIONS)  # type: ignore[arg-type]
    with_seed = _parse_all(monkeypatch, seeded)
    with_built = _parse_all(monkeypatch, built)
    assert with_seed == with_built
    assert any(span.line > 1 for _, spans, _ in with_seed for span in spans)  # type: ignore[attr-defined]
    assert any(diags for _, _, diags in with_seed)


def test_mismatching_tables_are_not_used(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(parse, "seed_header", lambda grammar: b"another grammar\n")
    assert parse._from_seed(parse._grammar_text()) is None
