"""Symbolic solution of the MTSA game (§3.3–3.6): reachability, the GR(1) fixpoint, MTSA's
controller.

The game itself — leaf machines encoded one by one, the product as a partitioned relation —
is :class:`symbolic_game.SymbolicGame`; the fixpoint is :func:`fixpoint.gr1_winning` over
``CPre`` of §3.4; the controller comes from symbolic rank layers and an enumeration of the
controller's own states (:mod:`symbolic_strategy`).  The supervisory non-blocking game (§3.9)
still ranks an explicit subgame (:func:`subgame`): its director is small by construction.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from typing import Any

from iterplan_compiler.ir.lts import ERROR, LTS
from iterplan_compiler.synthesis.encode import GameSpec, evaluate
from iterplan_compiler.synthesis.explicit import ExplicitGame, explore_product
from iterplan_compiler.synthesis.fixpoint import Gr1Fixpoint, gr1_winning
from iterplan_compiler.synthesis.macro import solve_macro
from iterplan_compiler.synthesis.options import GameMode, MacroSteps, VariableOrder
from iterplan_compiler.synthesis.recode import recode_leaves
from iterplan_compiler.synthesis.strategy import StrategyKind, extract_director
from iterplan_compiler.synthesis.symbolic_game import SymbolicGame, quotient_leaves
from iterplan_compiler.synthesis.symbolic_strategy import extract_gr1_strategy
from iterplan_compiler.synthesis.turns import Reorder, TurnSolution, solve_turns

__all__ = ["SymbolicGame", "VariableOrder", "nonblocking_symbolic", "solve_symbolic", "subgame"]

#: reachability is abandoned (the fixpoint then runs over all valid states) once the reached
#: set's BDD grows past this many nodes — see :meth:`SymbolicGame.reachable`
REACH_MAX_NODES = 200_000
#: games with more reachable states get no counter-strategy trace
EXPLAIN_MAX_STATES = 50_000
_TOO_LARGE = "\n(game too large for a counter-strategy trace; try a smaller instance)"


def subgame(g: SymbolicGame, region: Any, *, limit: int | None = None) -> ExplicitGame:
    """The explicit game on the states reachable from the initial state through ``region``.

    Edges leaving ``region`` go to states without successors (and ERROR to one sink), so the
    ranks of region states are those of the full game.  Membership comes from the BDD once
    (see :func:`_membership`: usually nothing, or the few losing states, is decoded); the
    edges come from an explicit exploration of the components that expands region states
    only — far cheaper than enumerating the transition relation.
    """
    spec = g.spec
    members = _membership(g, region)
    tuples_, pedges, _ = explore_product(spec.components, max_states=limit, expand=members)
    n = len(tuples_)
    has_error = any(t == ERROR for out in pedges for _, t in out)
    sink = n if has_error else None
    edges: list[list[tuple[str, int]]] = [
        [(a, sink if t == ERROR else t) for a, t in out] for out in pedges]  # type: ignore[misc]
    inside = [True] * n if members is None else [members(t) for t in tuples_]
    tuples: list[tuple[int, ...] | None] = list(tuples_)
    if sink is not None:
        tuples.append(None)
        edges.append([])
        inside.append(False)
    total = len(edges)
    ctrl = spec.controllable
    env = [any(a not in ctrl for a, _ in edges[s]) for s in range(total)]
    vals = [g.fluent_values(t) if t is not None else None for t in tuples]

    def sets(formulas: tuple) -> list[frozenset[int]]:
        return [frozenset(s for s in range(n) if (v := vals[s]) is not None and inside[s]
                          and evaluate(f, v)) for f in formulas]

    everything = frozenset(range(n))
    A = sets(spec.assumptions) or [everything]
    G = sets(spec.guarantees) or [everything]
    fs = sets(spec.failures)
    F = frozenset().union(*fs) if fs else frozenset()
    game = ExplicitGame(total, 0, edges, env, ctrl, A, G, F, spec.alphabet, tuples, sink,
                        spec.mode)
    game.inside = inside  # type: ignore[attr-defined]
    return game


def _membership(g: SymbolicGame, region: Any) -> Callable[[tuple[int, ...]], bool] | None:
    """Membership test for ``region`` on reachable state tuples (None: every one is inside).

    Decoding a BDD into tuples costs a Python dict per state, so the smaller side is
    enumerated: nothing when the region holds every reachable non-ERROR state (the usual
    realizable case), the losing states when they are fewer, else the region itself.
    """
    b = g.bdd
    reach = g.reach if g.reach is not None else g.reachable()
    live = reach & ~g.error
    outside = live & ~region
    if outside == b.false:
        return None
    if g.count(outside) < g.count(region & live):
        losing = {g.decode(a, g.cur) for a in b.pick_iter(outside, care_vars=g.cur_vars)}
        return lambda t: t not in losing
    members = {g.decode(a, g.cur) for a in b.pick_iter(region & live, care_vars=g.cur_vars)}
    return members.__contains__


def nonblocking_symbolic(g: SymbolicGame, care: Any, marked: Any) -> Any:
    """``νZ. CoReach_Z(marked)`` restricted to safe states (see strategy.nonblocking_region)."""
    Z = care & ~g.error
    while True:
        safe = Z & g.cpre(Z)
        co = marked & safe
        while True:
            nco = co | (safe & g.pre_any(co))
            if nco == co:
                break
            co = nco
        if co == Z:
            return Z
        Z = co


def solve_symbolic(spec: GameSpec, stats: dict[str, Any], say: Callable[[str], None], *,
                   explain: bool, name: str,
                   order: VariableOrder = VariableOrder.CLUSTERED,
                   permissive: bool = False, quotient: bool = True,
                   started: float | None = None,
                   kind: StrategyKind = StrategyKind.PERMISSIVE,
                   macro: MacroSteps = MacroSteps.AUTO,
                   verdict_only: bool = False
                   ) -> tuple[bool, LTS | None, str]:
    """Symbolic solve + MTSA controller extraction; returns (realizable, controller, why).

    With ``quotient`` the body machines are first replaced by their bisimulation quotients
    (:func:`symbolic_game.quotient_leaves`) and, in the ``clustered`` order, renumbered to
    fluent-aligned codes (:func:`recode.recode_leaves`); an unrealizable game to be explained
    is then solved again without either, so the counter-strategy trace names the machines'
    own states.

    ``started`` (``perf_counter`` time; default: this call) is when synthesis began: the
    verdict is reported through ``say`` as soon as the fixpoint decides it
    (:func:`_announce`), before the controller is extracted.  ``kind``: MTSA's controller
    or the GR(1) director (:mod:`symbolic_strategy`); ``macro``: compress controller-only
    chains (:mod:`macro`) where that applies; ``verdict_only``: stop at the verdict (no
    controller: ``(True, None, "")``; an unrealizable game is still explained with
    ``explain``)."""
    t = time.perf_counter()
    started = t if started is None else started
    said = False  # the verdict was said by the quotiented solve below
    if quotient and spec.mode is GameMode.GR1:  # the director (§3.9) is ranked explicitly as is
        qspec = _quotiented(spec, order, stats)
        if qspec is not spec:
            ok, ctrl, why = solve_symbolic(qspec, stats, say, explain=False, name=name,
                                           order=order, permissive=permissive,
                                           quotient=False, started=started,
                                           kind=kind, macro=macro, verdict_only=verdict_only)
            states = stats.get("game_states")
            if ok or not explain:
                return ok, ctrl, why
            if not isinstance(states, int) or states > EXPLAIN_MAX_STATES:
                return ok, ctrl, why + _TOO_LARGE  # no trace past the bound anyway
            said = True
    nonblocking = spec.mode is GameMode.NONBLOCKING
    g = _encode(spec, order, stats, t)
    turned = None
    if not nonblocking and macro is MacroSteps.AUTO:
        g, turned = _turns_first(g, order, stats, say, started, said)
        said = said or turned is not None
        if turned is not None and verdict_only and (turned.realizable or not explain):
            return turned.realizable, None, "" if turned.realizable else _uncounted()
    goals = _goals(g)
    reach = _reach(g, stats, say, nonblocking, turned.reachable() if turned else None)
    care = g.live if reach is None else reach
    t = time.perf_counter()
    if nonblocking:
        return _solve_nonblocking(g, care, stats, explain, name, t, say, started,
                                  verdict_only)
    W, complete, iterations = _winning(g, care, goals, turned, explain, stats, say, macro)
    stats["t_solve"] = time.perf_counter() - t
    stats["fixpoint_iterations"] = iterations
    stats["winning_bdd_nodes"] = len(W)
    _peak(g, stats)
    if not said:
        _announce((g.init & W) != g.bdd.false, started, stats, say)
    if (g.init & W) == g.bdd.false:
        return False, None, _lost(g, care, W, goals, explain, complete)
    if reach is not None:
        stats["winning_states"] = g.count(W)
        if kind is StrategyKind.PERMISSIVE and not verdict_only:  # (a director: far below)
            _check_controller_bound(stats["winning_states"] * len(goals), name)
    if verdict_only:
        return True, None, ""
    t = time.perf_counter()
    ctrl = extract_gr1_strategy(g, W, name, spec.alphabet, kind, permissive=permissive,
                                progress=say)
    stats["t_extract"] = time.perf_counter() - t
    _peak(g, stats)
    return True, ctrl, ""


def _lost(g: SymbolicGame, care: Any, W: Any, goals: list[Any], explain: bool,
          complete: bool) -> str:
    """An unrealizable verdict's message (and, with ``explain``, the play)."""
    if explain and not complete:
        # stopped early (must_contain): W is a superset of the winning region; the
        # explanation's counts and play need the exact one (as the explicit solver has)
        W = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=care & g.live).winning & care
    return _explain_symbolic(g, care, W, explain, exact=explain or complete)


def _quotiented(spec: GameSpec, order: VariableOrder, stats: dict[str, Any]) -> GameSpec:
    """``spec`` with its body machines' quotients and (``clustered``) fluent-aligned codes
    (:func:`solve_symbolic`); ``spec`` itself where neither changes anything."""
    qspec = quotient_leaves(spec)
    if qspec is not spec:
        stats["body_states"] = [c.num_states for c in spec.components[:_nbody(spec)]]
        stats["body_quotient_states"] = [c.num_states
                                         for c in qspec.components[:_nbody(spec)]]
    if order is VariableOrder.CLUSTERED:
        # fluent-aligned codes, shared fluent variables (recode.py): the same game
        qspec = recode_leaves(qspec)
    return qspec


def _uncounted() -> str:
    """An unrealizable verdict's message when the losing states were not counted."""
    from iterplan_compiler.synthesis.explain import losing_head

    return losing_head(None, None)


def _goals(g: SymbolicGame) -> list[Any]:
    """The fixpoint's goals: each guarantee (or every live state) with the failures."""
    return [gj | g.failures for gj in (g.guarantees or [g.live])]


def _turns_first(g: SymbolicGame, order: VariableOrder, stats: dict[str, Any],
                 say: Callable[[str], None], started: float, said: bool
                 ) -> tuple[SymbolicGame, TurnSolution | None]:
    """The turn game (:mod:`turns`) where it applies, its verdict said at once — before the
    full game's reachable set, which the controller extraction still needs.  In the default
    order the variable order may be learned on the way (:mod:`learn_order`): the game is then
    built again in the learned order and solved from the start; the game solved is returned."""
    t = time.perf_counter()
    turned = solve_turns(g, g.assumptions, _goals(g), say=say, stats=stats,
                         learn=order is VariableOrder.CLUSTERED)
    if isinstance(turned, Reorder):
        say(f"turn steps: variable order learned from the turn starts ({turned.nodes} "
            f"nodes); building the game again in it")
        stats["order_learned_at"] = turned.nodes
        g = _encode(g.spec, order, stats, time.perf_counter(), names=turned.names)
        turned = solve_turns(g, g.assumptions, _goals(g), say=say, stats=stats)
    assert not isinstance(turned, Reorder)  # learning was not asked for
    if turned is not None:
        stats["t_turns"] = time.perf_counter() - t
        if not said:
            _announce(turned.realizable, started, stats, say)
    return g, turned


def _winning(g: SymbolicGame, care: Any, goals: list[Any], turned: TurnSolution | None,
             explain: bool, stats: dict[str, Any], say: Callable[[str], None],
             macro: MacroSteps) -> tuple[Any, bool, dict[str, int]]:
    """The winning region on ``care``, whether it is exact (not a superset from a fixpoint
    stopped early), and the fixpoint's iteration counts.  After the turn game: the full
    region when a controller or an explanation needs it, else the turn starts' region."""
    if turned is not None:
        complete = turned.realizable or explain
        return turned.full_winning(care, exact=complete), complete, turned.iterations
    fp = _fixpoint(g, care & g.live, goals, stats, say, macro)
    return fp.winning & care, fp.complete, fp.iterations


def _fixpoint(g: SymbolicGame, care: Any, goals: list[Any], stats: dict[str, Any],
              say: Callable[[str], None], macro: MacroSteps) -> Gr1Fixpoint:
    """The GR(1) fixpoint of the game on ``care``: over the compressed game
    (:func:`macro.solve_macro`) where that applies, else over the full game.  Not tried
    without the reachable set (``care`` = every live state): the chains of unreachable
    states are unstructured (GyroLTL_595 at the reach cap: no macro verdict in 90 s)."""
    if macro is not MacroSteps.OFF and g.reach is not None:
        fp = solve_macro(g, care, g.assumptions, goals, say=say, stats=stats)
        if fp is not None:
            return fp
    return gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=care,
                       must_contain=g.init, progress=say, cpre_lost=g.cpre_lost_chained,
                       cpre_gained=g.cpre_gained)


def _encode(spec: GameSpec, order: VariableOrder, stats: dict[str, Any],
            t: float, names: tuple[str, ...] | None = None) -> SymbolicGame:
    """The symbolic game of ``spec`` (leaves encoded one by one; ``names``: a learned
    variable order, :mod:`learn_order`)."""
    g = SymbolicGame(spec, order=order, names=names)
    stats["bdd_backend"] = type(g.bdd).__module__
    stats["order"] = order
    stats["t_encode"] = time.perf_counter() - t
    return g


def _reach(g: SymbolicGame, stats: dict[str, Any], say: Callable[[str], None],
           nonblocking: bool, known: Any = None) -> Any:
    """The game's reachable set (None: abandoned at :data:`REACH_MAX_NODES`; ``known``:
    already built, by the turn game); the framed relations are restricted to it."""
    t = time.perf_counter()
    if known is not None:
        reach = g.reach = known
    else:
        reach = g.reachable(max_nodes=None if nonblocking else REACH_MAX_NODES)
    stats["t_reach"] = time.perf_counter() - t
    if reach is not None:
        g.restrict(reach)
        stats["game_states"] = g.count(reach & g.live) + (
            1 if (reach & g.error) != g.bdd.false else 0)
    else:
        stats["game_states"] = "unknown (reachable set not built)"
    stats["trans_bdd_nodes"] = g.relation_nodes()
    stats["bdd_vars"] = len(g.bdd.vars)
    say(f"symbolic game: {stats['game_states']} reachable states, "
        f"|T| = {stats['trans_bdd_nodes']} nodes in {len(g.groups)} groups")
    return reach


def _announce(realizable: bool, started: float, stats: dict[str, Any],
              say: Callable[[str], None]) -> None:
    """``verdict: realizable|unrealizable at N s`` (seconds since synthesis began), said as
    soon as the fixpoint decides: on the big SYNTECH15 games the explicit controller
    enumeration can take far longer than the verdict (issue 12's target is the verdict
    within 60 s), so a caller with a deadline still learns it.  Also ``stats["verdict_at"]``."""
    secs = time.perf_counter() - started
    stats["verdict_at"] = secs
    say(f"verdict: {'realizable' if realizable else 'unrealizable'} at {secs:.1f} s")


def _nbody(spec: GameSpec) -> int:
    return spec.num_plant + spec.num_safety


def _peak(g: SymbolicGame, stats: dict[str, Any]) -> None:
    """Record the manager's peak live node count (CUDD only)."""
    try:
        with warnings.catch_warnings():  # dd warns about an unrelated key ('mem')
            warnings.simplefilter("ignore")
            peak = int(g.bdd.statistics()["peak_live_nodes"])
    except Exception:  # noqa: BLE001 - autoref has other statistics keys
        peak = len(g.bdd)
    stats["peak_bdd_nodes"] = max(peak, stats.get("peak_bdd_nodes", 0))


def _check_controller_bound(bound: int, name: str) -> None:
    """--max-states before the explicit controller enumeration: the controller's states are
    (winning state, goal counter) pairs, so ``bound`` = |reachable winning region| x |goals|
    bounds its size.  Checked up front, so a limit too small for the controller is reported in
    seconds instead of after enumerating up to it (an over-approximation: the message says
    so)."""
    from iterplan_compiler import limits

    cap = limits.current().max_states
    if bound > cap:
        raise limits.LimitReached("max_states", (
            f"the controller of {name or 'the game'} may have up to {bound:,} states (its "
            f"winning region times its goals), more than {cap:,}: {limits.hint('max_states')}"))


def _solve_nonblocking(g: SymbolicGame, reach: Any, stats: dict[str, Any], explain: bool,
                       name: str, t: float, say: Callable[[str], None], started: float,
                       verdict_only: bool = False) -> tuple[bool, LTS | None, str]:
    marked = g.guarantees[0] & reach
    W = nonblocking_symbolic(g, reach, marked)
    stats["t_solve"] = time.perf_counter() - t
    stats["winning_states"] = g.count(W)
    _announce((g.init & W) != g.bdd.false, started, stats, say)
    if (g.init & W) == g.bdd.false:
        return False, None, _explain_symbolic(g, reach, W, explain)
    if verdict_only:
        return True, None, ""
    t = time.perf_counter()
    from iterplan_compiler import limits

    game = subgame(g, W, limit=limits.current().max_states)  # explored explicitly
    region = frozenset(s for s in range(game.num_states) if game.inside[s])  # type: ignore[attr-defined]
    ctrl = extract_director(game, region, game.guarantees[0], name, g.spec.alphabet)
    stats["t_extract"] = time.perf_counter() - t
    return True, ctrl, ""


def _explain_symbolic(g: SymbolicGame, reach: Any, W: Any, explain: bool,
                      exact: bool = True) -> str:
    from iterplan_compiler.synthesis.explain import losing_head

    if g.reach is None or not exact:
        head = losing_head(None, None)
    else:
        head = losing_head(g.count(reach & ~W & ~g.error), g.count(reach & ~g.error))
    if not explain:
        return head
    if g.reach is None or g.count(reach) > EXPLAIN_MAX_STATES:
        return head + _TOO_LARGE
    from iterplan_compiler.synthesis.explain import explain_losing
    from iterplan_compiler.synthesis.explicit import build_game

    game = build_game(g.spec)
    win = set()
    for s, tup in enumerate(game.tuples):
        if tup is not None and (g.state_cube(tup) & W) != g.bdd.false:
            win.add(s)
    try:
        return explain_losing(g.spec, game, frozenset(win))
    except Exception as exc:  # noqa: BLE001 - an explanation bug must not hide the verdict
        return head + f"\n(no counter-strategy trace: {exc})"
