"""The enumeration's fast paths (synthesis/symbolic_eval.py, quotient_leaves) against their
plain definitions: compiled BDD walks vs ``dd`` membership, the rank graph vs the layers,
memoised product moves vs explicit.ProductMoves, and the controller with and without the
bisimulation quotient of the body machines."""

from __future__ import annotations

import random
import tempfile

import pytest
from hypothesis import HealthCheck, given, settings
from test_agreement import problems

from iterplan_compiler.ir.lts import make_lts
from iterplan_compiler.ir.minimise import bisimilar
from iterplan_compiler.symbolic.bdd import BitVec, declare_interleaved, new_manager
from iterplan_compiler.synthesis.encode import prepare
from iterplan_compiler.synthesis.explicit import ProductMoves
from iterplan_compiler.synthesis.symbolic_eval import CachedMoves, CompiledSets, RankTable
from iterplan_compiler.synthesis.symbolic_game import quotient_leaves


def _manager(backend):
    try:
        return new_manager(backend=backend)
    except ImportError:
        pytest.skip(f"dd.{backend} not installed")


def _random_set(bdd, vecs, rng, n_terms):
    u = bdd.false
    for _ in range(n_terms):
        cube = bdd.true
        for vec in vecs:
            for name in vec.names:
                r = rng.random()
                if r < 0.3:
                    cube &= bdd.var(name)
                elif r < 0.6:
                    cube &= ~bdd.var(name)
        u |= cube
    return u


def _states(widths):
    out = [()]
    for w in widths:
        out = [s + (v,) for s in out for v in range(1 << w)]
    return out


@pytest.mark.parametrize("backend", ["cudd", "autoref"])
@pytest.mark.parametrize("seed", range(6))
def test_compiled_membership_is_bdd_membership(backend, seed):
    bdd = _manager(backend)
    rng = random.Random(seed)
    widths = [2, 1, 3]
    vecs: list[BitVec] = [declare_interleaved(bdd, f"s{k}", w)[0] for k, w in enumerate(widths)]
    sets = CompiledSets(bdd, vecs)
    us = [_random_set(bdd, vecs, rng, rng.randint(0, 6)) for _ in range(4)]
    us += [~us[0], bdd.true, bdd.false]
    _check_members(bdd, vecs, widths, sets, us)


def _check_members(bdd, vecs, widths, sets, us):
    """Every state against every set: the compiled walk against ``dd``'s ``<=``."""
    roots = [sets.add(u) for u in us]
    for s in _states(widths):
        cube = bdd.true
        for vec, v in zip(vecs, s, strict=True):
            cube &= vec.eq(bdd, v)
        for u, root in zip(us, roots, strict=True):
            assert sets.member(root, s) == (cube <= u), (s, u)


@pytest.mark.parametrize("backend", ["cudd", "autoref"])
@pytest.mark.parametrize("seed", range(4))
def test_membership_with_components_split_in_the_order(backend, seed):
    """A component's bits need not be adjacent in the variable order (shared fluent
    variables of recoded machines sit where first declared)."""
    bdd = _manager(backend)
    rng = random.Random(seed)
    bdd.declare("a0", "b0", "a1", "c0", "b1", "a2")
    vecs = [BitVec(("a0", "a1", "a2")), BitVec(("b0", "b1")), BitVec(("c0",))]
    sets = CompiledSets(bdd, vecs)
    us = [_random_set(bdd, vecs, rng, rng.randint(1, 6)) for _ in range(4)]
    _check_members(bdd, vecs, [3, 2, 1], sets, us)


@pytest.mark.parametrize("backend", ["cudd", "autoref"])
@pytest.mark.parametrize("seed", range(4))
def test_rank_table_is_first_layer(backend, seed):
    bdd = _manager(backend)
    rng = random.Random(seed)
    widths = [3, 2]
    vecs: list[BitVec] = [declare_interleaved(bdd, f"s{k}", w)[0] for k, w in enumerate(widths)]
    layers = []
    acc = bdd.false
    for _ in range(rng.randint(1, 9)):  # nested layers, some repeated
        acc |= _random_set(bdd, vecs, rng, rng.randint(0, 2))
        layers.append(acc)
    sets = CompiledSets(bdd, vecs)
    table = RankTable(sets, layers, "_r", inf=10**9)
    for s in _states(widths):
        cube = bdd.true
        for vec, v in zip(vecs, s, strict=True):
            cube &= vec.eq(bdd, v)
        want = next((k for k, u in enumerate(layers) if cube <= u), 10**9)
        assert table.rank(s) == want, s



def _churn(bdd, vecs, rng):
    """Free what nobody holds and let the library reuse its node ids: ``dd.autoref``
    collects on request; CUDD collects (and then recycles node addresses) once enough dead
    nodes pile up, so make ~200 garbage sets."""
    if hasattr(bdd, "collect_garbage"):
        bdd.collect_garbage()
        return
    names = [n for vec in vecs for n in vec.names]
    for _ in range(200):
        u = bdd.false
        for _ in range(12):
            cube = bdd.true
            for name in names:
                r = rng.random()
                if r < 0.4:
                    cube &= bdd.var(name)
                elif r < 0.8:
                    cube &= ~bdd.var(name)
            u |= cube
        del u


@pytest.mark.parametrize("backend", ["cudd", "autoref"])
@pytest.mark.parametrize("seed", range(2))
def test_compiled_sets_survive_garbage_collection(backend, seed):
    """Regression: the tables are keyed by node id, and a BDD compiled from a temporary
    (as RankTable's rank graph is) used to be freed; after a garbage collection its ids
    named other nodes, so a set compiled later was answered with an earlier set's table."""
    import gc

    bdd = _manager(backend)
    rng = random.Random(seed)
    widths = [4, 3, 4, 3]
    vecs: list[BitVec] = [declare_interleaved(bdd, f"s{k}", w)[0] for k, w in enumerate(widths)]
    sets = CompiledSets(bdd, vecs)
    for _ in range(6):
        sets.add(_random_set(bdd, vecs, rng, 10))  # nobody else holds these
        gc.collect()
        _churn(bdd, vecs, rng)
    kept = [_random_set(bdd, vecs, rng, 10) for _ in range(10)]
    roots = [sets.add(u) for u in kept]
    for s in _states(widths)[::7]:
        point: dict[str, bool] = {}
        for vec, v in zip(vecs, s, strict=True):
            point.update(vec.assign(v))
        for u, root in zip(kept, roots, strict=True):
            assert sets.member(root, s) == (bdd.let(point, u) == bdd.true), s


@pytest.mark.parametrize("memo_max_owners", [4, 1, 0])
def test_cached_moves_are_product_moves(memo_max_owners, monkeypatch):
    """Same moves, same order, with the memo and without it (``MEMO_MAX_OWNERS``: 0 and 1
    synchronise the two- and three-owner actions directly, nondeterministic ``x`` too)."""
    from iterplan_compiler.synthesis import symbolic_eval

    monkeypatch.setattr(symbolic_eval, "MEMO_MAX_OWNERS", memo_max_owners)
    a = make_lts("A", 3, [(0, "x", 1), (1, "y", 2), (2, "x", 0), (1, "tau", 0), (0, "z", -1)],
                 {"x", "y", "z"})
    b = make_lts("B", 2, [(0, "x", 1), (0, "x", 0), (1, "y", 0), (1, "w", 1)],
                 {"x", "y", "w"})
    c = make_lts("C", 2, [(0, "y", 1), (1, "y", 0), (0, "z", 0)], {"y", "z"})
    plain, cached = ProductMoves([a, b, c]), CachedMoves([a, b, c])
    assert cached.start == plain.start
    for s in _states([2, 1, 1]):
        if s[0] > 2:
            continue
        for _ in range(2):  # second round from the memo
            assert cached.moves(s) == plain.moves(s), s


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_quotient_keeps_the_controller(prob):
    """Solving over the quotiented body machines gives the same verdict and a bisimilar
    controller (module doc of symbolic_game.quotient_leaves)."""
    from iterplan_compiler.synthesis.driver import _minimise
    from iterplan_compiler.synthesis.game import solve_symbolic

    spec = prepare(prob)
    runs = [solve_symbolic(spec, {}, lambda _m: None, explain=False, name="C", quotient=q)
            for q in (True, False)]
    assert runs[0][0] == runs[1][0]
    if runs[0][0]:
        assert bisimilar(_minimise(runs[0][1]), _minimise(runs[1][1]))


def test_quotient_shrinks_fire_patrol_uav():
    from iterplan_compiler.experiments.catalog import explicit_fire_patrol
    from iterplan_compiler.frontend import load

    with tempfile.NamedTemporaryFile("w", suffix=".lts", delete=False) as fh:
        fh.write(explicit_fire_patrol(4))
    model, _ = load(fh.name)
    problem, _ = model.synthesis_problem("ExplicitFirePatrol")
    spec = prepare(problem)
    q = quotient_leaves(spec)
    uav = [c.name for c in spec.components].index("UAV")
    assert spec.components[uav].num_states == 4 + 16
    assert q.components[uav].num_states == 1 + 4
    nbody = spec.num_plant + spec.num_safety
    assert q.components[nbody:] == spec.components[nbody:]  # fluent monitors untouched
