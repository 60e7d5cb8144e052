"""Fluent-aligned state codes (synthesis/recode.py): every feature found is a fluent the
machine really tracks, the recoded machine is the same machine, and recoding (with the
shared feature variables of symbolic_game) keeps the verdict and the controller."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from test_agreement import lts_strategy, problems

from iterplan_compiler.ir.lts import ERROR, make_lts
from iterplan_compiler.ir.minimise import bisimilar
from iterplan_compiler.synthesis.encode import prepare
from iterplan_compiler.synthesis.recode import (
    ERROR_BIT,
    _feature,
    codes,
    features,
    recode_leaves,
    recode_machine,
)
from iterplan_compiler.synthesis.symbolic_game import SymbolicGame, quotient_leaves

SYNTECH = Path(__file__).resolve().parents[3] / "shared" / "benchmarks" / "syntech15"


def _resets(c, a):
    """The ``T`` that :func:`recode._feature` guesses for key ``a``."""
    targets = {b: {t for _, x, t in c.transitions if x == b and t != ERROR} for b in c.alphabet}
    return {b for b, ts in targets.items() if b != a and ts and not ts & targets[a]}, targets


@settings(max_examples=300, deadline=None)
@given(lts_strategy("M", 6, error_ok=True))
def test_every_feature_is_a_tracked_fluent(c):
    """``a`` enters φ = 1, the guessed resets enter φ = 0, every other move keeps φ."""
    for key, phi in features(c):
        a = key[1:key.index("|")]
        resets, targets = _resets(c, a)
        assert _feature(c, a, targets) == (key, phi)
        assert key.endswith(str(phi[c.initial]))
        for s, b, t in c.transitions:
            if t == ERROR:
                continue
            if b == a:
                assert phi[t] == 1
            elif b in resets:
                assert phi[t] == 0
            else:
                assert phi[t] == phi[s], (s, b, t)


@settings(max_examples=300, deadline=None)
@given(lts_strategy("M", 6, error_ok=True))
def test_recoded_machine_is_the_same_machine(c):
    """An injective renumbering whose low bits are the feature values; ERROR is the error
    bit alone; the machine is unchanged up to that renumbering."""
    rec = recode_machine(c)
    if rec is None:
        assert codes(c) is None
        return
    out, keys = rec
    code, width, feats = codes(c)
    assert len(keys) == width and [k for k in keys[:len(feats)]] == [k for k, _ in feats]
    assert len(set(code)) == len(code)  # injective
    assert all(0 <= x < out.num_states for x in code)
    for s in range(c.num_states):
        for i, (_, phi) in enumerate(feats):
            assert (code[s] >> i) & 1 == phi[s]
    mapped = {(code[s], a, ERROR if t == ERROR else code[t]) for s, a, t in c.transitions}
    assert set(out.transitions) == mapped
    assert out.initial == code[c.initial] and out.alphabet == c.alphabet
    if c.has_error:
        assert keys[-1] == ERROR_BIT and out.num_states == 1 << (width - 1)
        assert all(not (x >> (width - 1)) & 1 for x in code)
    assert bisimilar(out, c)


def test_fluent_machine_gets_value_bits():
    """A machine tracking ``<on, {off}>`` and ``<up, {down}>`` (states numbered scrambled)
    gets those values as its code bits, no residual bit."""
    num = {(0, 0): 2, (1, 0): 0, (0, 1): 3, (1, 1): 1}
    trans = []
    for (on, up), s in num.items():
        trans += [(s, "on", num[(1, up)]), (s, "off", num[(0, up)]),
                  (s, "up", num[(on, 1)]), (s, "down", num[(on, 0)]), (s, "tick", s)]
    c = make_lts("M", 4, trans, initial=num[(0, 0)])
    code, width, feats = codes(c)
    assert width == 2 and len(feats) == 2
    for (on, up), s in num.items():
        vals = {k: (code[s] >> i) & 1 for i, (k, _) in enumerate(feats)}
        by_fluent = {k.split("|")[0][1:]: v for k, v in vals.items()}
        # the key action of each feature is whichever of on/off (up/down) sorts first
        got_on = by_fluent["off"] ^ 1 if "off" in by_fluent else by_fluent["on"]
        got_up = by_fluent["down"] ^ 1 if "down" in by_fluent else by_fluent["up"]
        assert (got_on, got_up) == (on, up)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_recoding_keeps_the_controller(prob):
    """Same verdict and bisimilar controllers with and without the recoded, shared-variable
    encoding (quotient off in both, so recoding is the only difference)."""
    from iterplan_compiler.synthesis.driver import _minimise
    from iterplan_compiler.synthesis.game import solve_symbolic

    spec = prepare(prob)
    rec = recode_leaves(spec)
    runs = [solve_symbolic(s, {}, lambda _m: None, explain=False, name="C", quotient=False)
            for s in (rec, spec)]
    assert runs[0][0] == runs[1][0]
    if runs[0][0]:
        assert bisimilar(_minimise(runs[0][1]), _minimise(runs[1][1]))


@pytest.mark.skipif(not SYNTECH.exists(), reason="SYNTECH15 benchmark not present")
def test_syntech_shares_fluents_and_keeps_the_controller():
    """GyroLTL_390: several safety automata track the same fluents, which then share one
    variable; verdict and controller as without recoding."""
    from iterplan_compiler import limits
    from iterplan_compiler.pipeline import load_model_with_sources
    from iterplan_compiler.synthesis.driver import _minimise
    from iterplan_compiler.synthesis.game import solve_symbolic

    limits.set_limits(max_temporal_ops=24)
    try:
        model, _, _ = load_model_with_sources(str(SYNTECH / "GyroLTL_390_GyroAspect.fsp"))
        problem, _ = model.synthesis_problem("Control")
        spec = quotient_leaves(prepare(problem))
        rec = recode_leaves(spec)
        g = SymbolicGame(rec)
        names = [n for vec in g.cur for n in vec.names]
        assert len(names) - len(set(names)) >= 10  # shared feature variables
        runs = [solve_symbolic(s, {}, lambda _m: None, explain=False, name="C",
                               quotient=False) for s in (rec, spec)]
    finally:
        limits.set_limits()
    assert runs[0][0] and runs[1][0]
    assert bisimilar(_minimise(runs[0][1]), _minimise(runs[1][1]))
