"""Grammar extensions beyond the corpus: several `foreach` bindings, composite prefixes that
bind (`[i:R]:P(i)`), literal numbers after a dot (`a.1`)."""

from __future__ import annotations

from iterplan_compiler.diagnostics import has_errors
from iterplan_compiler.frontend import syntax as S
from iterplan_compiler.frontend.parse import parse_text
from iterplan_compiler.frontend.printer import print_spec
from iterplan_compiler.pipeline import load_model as load

TEXT = """const N = 2
P(I=0) = (a[I] -> b.1 -> P).
Q = (foreach [i:0..1][j:0..1] c[i][j] -> Q | d -> Q).
||C = ([i:1..N]:P(i) || s.1:P(0)).
||E = (forall [k:1..2] ([j:1..2]:P(j))).
"""


def _model():
    model, diags = load("g.lts", TEXT)
    assert model is not None and not has_errors(diags), [d.message for d in diags]
    return model


def test_foreach_with_several_bindings():
    spec, _ = parse_text(TEXT)
    q = next(d for d in spec.decls if isinstance(d, S.ProcessDecl) and d.name == "Q")
    assert [b.var for b in q.body.foreach] == ["i", "j"]
    lts, _ = _model().build_lts("Q")
    assert set(lts.alphabet) == {"c.0.0", "c.0.1", "c.1.0", "c.1.1", "d"}
    assert lts.num_states == 1


def test_dotted_number_is_a_label_part():
    lts, _ = _model().build_lts("P")
    assert set(lts.alphabet) == {"a.0", "b.1"}


def test_binding_prefix_scopes_over_the_item():
    lts, _ = _model().build_lts("C")
    assert {"1.a.1", "2.a.2", "s.1.a.0"} <= set(lts.alphabet)
    assert "1.a.2" not in lts.alphabet


def test_extensions_round_trip():
    spec, diags = parse_text(TEXT)
    assert not has_errors(diags)
    spec2, diags2 = parse_text(print_spec(spec))
    assert not has_errors(diags2) and spec2.decls == spec.decls


def test_parser_cache_location(monkeypatch, tmp_path):
    from iterplan_compiler.frontend import parse

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.delenv("ITERPLAN_NO_CACHE", raising=False)
    path = parse._cache_file("start: A")
    assert isinstance(path, str) and path.startswith(str(tmp_path / "iterplan"))
    # one file per grammar: checkouts with different grammars do not overwrite each other
    other = parse._cache_file("start: B")
    assert isinstance(other, str) and other != path
    assert parse._cache_file("start: A") == path
    monkeypatch.setenv("ITERPLAN_NO_CACHE", "1")
    assert parse._cache_file("start: A") is False
