"""The on-disk cache of compiled safety LTSs (fltl/safety_cache.py): a hit gives exactly the
LTS and diagnostics of a fresh translation, keys ignore set order and spans but not meaning."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from iterplan_compiler.fltl import safety_cache
from iterplan_compiler.fltl.safety import safety_lts
from iterplan_compiler.pipeline import load_model

SPEC = """
fluent A = <a, b>
fluent B = <c, d>
ltl_property P = [](A -> X (!B W b))
constraint Q = [](B -> X !c)
ltl_property U = [](a && !a)
"""


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setattr(safety_cache, "WORTH_CACHING_S", 0.0)
    return tmp_path / "iterplan" / "safety"


def _formulas(text: str = SPEC):
    model, diags = load_model("t.lts", text=text)
    assert model is not None, diags
    return model


def _translate(model, name: str):
    nf = model.formulas[name]
    return safety_lts(nf, model.fluents, constraint=nf.kind == "constraint")


def test_hit_equals_fresh_translation(cache, monkeypatch):
    model = _formulas()
    names = ("P", "Q", "U")
    monkeypatch.setenv("ITERPLAN_NO_CACHE", "1")
    fresh = {n: _translate(model, n) for n in names}
    assert not cache.exists()
    monkeypatch.delenv("ITERPLAN_NO_CACHE")
    stored = {n: _translate(model, n) for n in names}
    assert len(list(cache.glob("lts-*.json"))) == 3
    # a hit must not translate at all
    monkeypatch.setattr("iterplan_compiler.fltl.safety.safety_dfa",
                        lambda *a, **k: pytest.fail("translated despite a cache hit"))
    for n in names:
        hit, hit_diags = _translate(model, n)
        for lts, diags in (fresh[n], stored[n]):
            assert hit == lts and hit is not None
            assert [(d.code, d.message, d.span) for d in hit_diags] == \
                [(d.code, d.message, d.span) for d in diags]
    assert [d.code for d in _translate(model, "U")[1]] == ["W0604"]


def test_key_ignores_spans_and_set_order_not_meaning(cache):
    a = _formulas()
    b = _formulas("\n\n" + SPEC.replace("fluent A = <a, b>", "fluent A = <a, b>  // moved"))
    key = lambda m, n: safety_cache.cache_key(m.formulas[n], m.fluents,  # noqa: E731
                                              constraint=False, max_states=1000)
    assert key(a, "P") == key(b, "P")
    c = _formulas(SPEC.replace("X (!B W b)", "X (!B W d)"))
    assert key(a, "P") != key(c, "P")
    assert key(a, "P") != safety_cache.cache_key(a.formulas["P"], a.fluents, constraint=True,
                                                 max_states=1000)


def test_key_is_the_same_in_another_process(cache):
    model = _formulas()
    here = safety_cache.cache_key(model.formulas["P"], model.fluents, constraint=False,
                                  max_states=1000)
    code = ("from iterplan_compiler.pipeline import load_model\n"
            "from iterplan_compiler.fltl import safety_cache\n"
            f"m, _ = load_model('t.lts', text={SPEC!r})\n"
            "print(safety_cache.cache_key(m.formulas['P'], m.fluents, constraint=False, "
            "max_states=1000))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={"PYTHONHASHSEED": "12345", "PATH": "/usr/bin:/bin",
                                          "ITERPLAN_NO_CACHE": "1"})
    assert out.stdout.strip() == here


def test_corrupt_entry_is_a_miss(cache):
    model = _formulas()
    fresh, _ = _translate(model, "P")
    for entry in cache.glob("*.json"):
        entry.write_text("{not json")
    again, _ = _translate(model, "P")
    assert again == fresh


def test_no_cache_env_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setenv("ITERPLAN_NO_CACHE", "1")
    monkeypatch.setattr(safety_cache, "WORTH_CACHING_S", 0.0)
    _translate(_formulas(), "P")
    assert not (Path(tmp_path) / "iterplan" / "safety").exists()


def test_the_build_reuses_the_dfa_of_the_open_alphabet_test(monkeypatch):
    """Elaboration's open-alphabet test and the build's translation of the same formula
    build its subset DFA once (fltl/safety.py recent_safety_dfa), even with no disk cache."""
    from iterplan_compiler.fltl import open_safety, safety

    monkeypatch.setenv("ITERPLAN_NO_CACHE", "1")
    monkeypatch.setattr(safety, "_RECENT_DFAS", type(safety._RECENT_DFAS)())
    built: list[str] = []
    real = safety.safety_dfa

    def counting(named, fluents, *, max_states=safety.DEFAULT_MAX_STATES):
        built.append(named.name)
        return real(named, fluents, max_states=max_states)

    monkeypatch.setattr(safety, "safety_dfa", counting)
    monkeypatch.setattr(open_safety, "safety_dfa", counting)
    model = _formulas()
    for name in ("P", "Q"):
        assert open_safety.open_safety_witness(model.formulas[name], model) is None
        fresh = len(built)
        lts, _ = _translate(model, name)
        assert lts is not None
        assert built.count(name) == 1 and len(built) == fresh  # reused, not rebuilt
    nf = model.formulas["P"]
    safety_lts(nf, model.fluents, constraint=False, max_states=50)   # another limit: rebuilt
    assert built.count("P") == 2
