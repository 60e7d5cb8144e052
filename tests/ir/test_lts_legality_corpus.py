"""Legality on the MTSA corpus files (LegalityAnalyserTest: which machines, which actions).

MTSA's test checks (MAKE_A, MAKE_B) inside FACTORY with controllable {makeA, ready} for
Factory.lts (legal) and NotLegal.lts (not legal), and (A, B) with controllable {a} for
NotLegal2.lts (not legal).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from iterplan_compiler.ir.legality import is_legal
from iterplan_compiler.pipeline import load_model as load

CORPUS = Path(__file__).resolve().parents[3] / "shared" / "conformance" / "mtsa" / "Legality"


def machines(file: str, *names: str):
    if not CORPUS.is_dir():
        pytest.skip(f"conformance corpus not present at {CORPUS}")
    model, diags = load(str(CORPUS / file))
    assert model is not None, [d.message for d in diags]
    out = []
    for n in names:
        m, diags = model.build_lts(n)
        assert m is not None, [d.message for d in diags]
        out.append(m)
    return out


@pytest.mark.parametrize("file,legal", [("Factory.lts", True), ("NotLegal.lts", False)])
def test_factory_files(file, legal):
    a, b, assemble = machines(file, "MAKE_A", "MAKE_B", "ASSEMBLE")
    res = is_legal(a, b, {"makeA", "ready"}, context=[assemble])
    assert res.legal is legal
    if not legal:
        assert res.witness.action == "makeB"


def test_not_legal_2():
    a, b = machines("NotLegal2.lts", "A", "B")
    res = is_legal(a, b, {"a"})
    assert not res.legal and res.witness.action == "b"
