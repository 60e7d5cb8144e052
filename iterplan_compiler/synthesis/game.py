"""The MTSA game (§3.2–3.4) encoded with BDDs, and its symbolic solution.

Encoding.  Component *k* (plant, safety machines, fluent monitors — see :mod:`encode`) gets
``bits_for(n_k + e_k)`` current/next variable pairs, where ``e_k = 1`` if it has ERROR moves:
code ``n_k`` then stands for its ERROR state.  The action is a binary index over the game
alphabet (plus ``tau`` if some component has internal moves).  The transition relation is a
conjunction of per-component relations — a component whose alphabet contains the action moves
by its own relation, the others are framed (``s' = s``); ``tau`` interleaves — and any state in
which some component is at its ERROR code has no successors (ERROR is a losing sink).

Variable orders (``order``): ``"clustered"`` (the default: action bits on top, then each
body component's bits with current/next interleaved, each fluent monitor's bit placed right
after the smallest component sharing most actions with it), ``"action_first"`` (the same
without moving fluents: they come last), ``"action_last"``, and ``"blocked"`` (all current
bits, then all next bits; the textbook bad order, kept for the benchmark).

Game (§3.3): ``Env(s) = ∃a,s'. T ∧ ¬ctrl(a)``;
``CPre(X) = (Env ∧ ∀s'. Tu → X') ∨ (¬Env ∧ ∃s'. Tc ∧ X')`` with ``Tu``/``Tc`` the
uncontrollable/controllable relations (action quantified out).  Dead ends satisfy neither
disjunct, so they lose.  The winning region comes from :func:`fixpoint.gr1_winning`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from iterplan_compiler.ir.lts import ERROR, LTS, TAU
from iterplan_compiler.symbolic.bdd import (
    BitVec,
    and_exists,
    bits_for,
    declare_interleaved,
    disjoin,
    new_manager,
    value_cubes,
)
from iterplan_compiler.synthesis.encode import GameSpec, evaluate
from iterplan_compiler.synthesis.explicit import ExplicitGame, explore_product, solve_ranks
from iterplan_compiler.synthesis.fixpoint import gr1_winning
from iterplan_compiler.synthesis.strategy import extract_controller, extract_director

ORDERS = ("action_first", "clustered", "action_last", "blocked")


class SymbolicGame:
    """BDD encoding of a :class:`GameSpec` (see the module docstring)."""

    def __init__(self, spec: GameSpec, *, bdd: Any = None, order: str = "clustered") -> None:
        if order not in ORDERS:
            raise ValueError(f"unknown order {order!r}")
        self.spec = spec
        self.bdd = bdd if bdd is not None else new_manager()
        b = self.bdd
        comps = spec.components
        self.has_tau = any(a == TAU for c in comps for _, a, _ in c.transitions)
        self.actions = sorted(spec.alphabet) + ([TAU] if self.has_tau else [])
        self.err_code = [c.num_states if c.has_error else None for c in comps]
        widths = [bits_for(c.num_states + (1 if c.has_error else 0)) for c in comps]
        aw = bits_for(len(self.actions))
        self.cur: list[BitVec] = []
        self.nxt: list[BitVec] = []
        if order == "blocked":
            cur_names = [tuple(f"s{k}_{i}" for i in range(w)) for k, w in enumerate(widths)]
            nxt_names = [tuple(f"s{k}_{i}'" for i in range(w)) for k, w in enumerate(widths)]
            b.declare(*[f"act_{i}" for i in range(aw)])
            for names in cur_names:
                b.declare(*names)
            for names in nxt_names:
                b.declare(*names)
            self.cur = [BitVec(n) for n in cur_names]
            self.nxt = [BitVec(n) for n in nxt_names]
        else:
            if order in ("action_first", "clustered"):
                b.declare(*[f"act_{i}" for i in range(aw)])
            vecs: dict[int, tuple[BitVec, BitVec]] = {}
            for k in self._declaration_order(order):
                vecs[k] = declare_interleaved(b, f"s{k}", widths[k])
            for k in range(len(widths)):
                self.cur.append(vecs[k][0])
                self.nxt.append(vecs[k][1])
            if order == "action_last":
                b.declare(*[f"act_{i}" for i in range(aw)])
        self.act = BitVec(tuple(f"act_{i}" for i in range(aw)))
        self.cur_vars = {v for vec in self.cur for v in vec.names}
        self.nxt_vars = {v for vec in self.nxt for v in vec.names}
        self.act_vars = set(self.act.names)
        self.prime = {c: n for cv, nv in zip(self.cur, self.nxt, strict=True)
                      for c, n in zip(cv.names, nv.names, strict=True)}
        self.unprime = {n: c for c, n in self.prime.items()}
        # Renaming maps with BDD-node values: dd.cudd's ``let`` then composes directly instead
        # of building a node per variable name on every call (halves the cost of renaming
        # small sets; no difference on large ones, where CUDD's own work dominates).
        self._prime_f = {c: b.var(n) for c, n in self.prime.items()}
        self._unprime_f = {n: b.var(c) for c, n in self.prime.items()}
        self._act_bdd = {a: self.act.eq(b, i) for i, a in enumerate(self.actions)}
        self.reach: Any = None  # set by reachable()
        self._build()

    def _declaration_order(self, order: str) -> list[int]:
        """Component order in the BDD: given order, or (``clustered``) each fluent monitor
        placed right after the body component sharing most actions with it, so a fluent's bit
        sits next to the state bits it is correlated with."""
        spec = self.spec
        nbody = spec.num_plant + spec.num_safety
        ks = list(range(len(spec.components)))
        if order != "clustered" or nbody == 0:
            return ks
        after: dict[int, list[int]] = {k: [] for k in range(nbody)}
        for f in range(nbody, len(ks)):
            alpha = spec.components[f].alphabet
            best = max(range(nbody), key=lambda k: (len(alpha & spec.components[k].alphabet),
                                                    -len(spec.components[k].alphabet), -k))
            after[best].append(f)
        out: list[int] = []
        for k in range(nbody):
            out.append(k)
            out.extend(after[k])
        return out

    # -- construction -------------------------------------------------------------------

    def _frame(self, k: int) -> Any:
        return self.cur[k].equal_to(self.bdd, self.nxt[k])

    def _component_relation(self, k: int, c: LTS, labels: set[str]) -> dict[str, Any]:
        """``{label: R(s_k, s_k')}`` for the given labels of component ``k``."""
        b = self.bdd
        terms: dict[str, list[Any]] = {}
        cur, nxt = self.cur[k], self.nxt[k]
        err = self.err_code[k]
        codes = c.num_states + (1 if err is not None else 0)
        src = value_cubes(b, cur, codes)
        dst = value_cubes(b, nxt, codes)
        for s, a, t in c.transitions:
            if a not in labels:
                continue
            terms.setdefault(a, []).append(src[s] & dst[err if t == ERROR else t])
        return {a: disjoin(b, ts) for a, ts in terms.items()}

    def _build(self) -> None:
        b = self.bdd
        spec = self.spec
        comps = spec.components
        ctrl = spec.controllable
        T = b.true
        valid = b.true
        err = b.false
        init = b.true
        tau_moves = b.false
        for k, c in enumerate(comps):
            codes = c.num_states + (1 if c.has_error else 0)
            valid &= self.cur[k].less_than(b, codes)
            init &= self.cur[k].eq(b, c.initial)
            if self.err_code[k] is not None:
                err |= self.cur[k].eq(b, self.err_code[k])
            rel = self._component_relation(k, c, set(c.alphabet) | {TAU})
            own = disjoin(b, [self._act_bdd[a] for a in c.alphabet])
            Tk = disjoin(b, [self._act_bdd[a] & rel[a] for a in sorted(c.alphabet) if a in rel])
            # actions outside the component's alphabet (and tau, handled below) frame it
            Tk |= ~own & self._frame(k)
            T &= Tk
            if TAU in rel:
                others = b.true
                for m in range(len(comps)):
                    if m != k:
                        others &= self._frame(m)
                tau_moves |= rel[TAU] & others
        if self.has_tau:
            tau = self._act_bdd[TAU]
            T = (T & ~tau) | (tau & tau_moves)
        any_action = b.false
        for a in self.actions:
            any_action |= self._act_bdd[a]
        self.valid = valid
        self.error = err & valid
        self.init = init
        self.trans = T & any_action & valid & ~err
        unc = b.false
        ctl = b.false
        for a in self.actions:
            if a in ctrl:
                ctl |= self._act_bdd[a]
            else:
                unc |= self._act_bdd[a]
        self.unc_actions, self.ctrl_actions = unc, ctl
        self.tu = b.exist(self.act_vars, self.trans & unc)
        self.tc = b.exist(self.act_vars, self.trans & ctl)
        self.env = b.exist(self.nxt_vars, self.tu)
        self.tc_own = self.tc & ~self.env  # controllable moves matter in controller states only
        self.t_any = self.tu | self.tc
        # goal sets over fluent-monitor bits
        nbody = spec.num_plant + spec.num_safety
        val = {name: b.var(self.cur[nbody + i].names[0])
               for i, name in enumerate(spec.fluent_names)}

        def sets(formulas: tuple) -> list[Any]:
            return [evaluate(f, val, true=b.true, false=b.false, neg=lambda x: ~x) & ~err
                    for f in formulas]

        self.assumptions = sets(spec.assumptions)
        self.guarantees = sets(spec.guarantees)
        fs = sets(spec.failures)
        self.failures = b.false
        for f in fs:
            self.failures |= f

    # -- operators ----------------------------------------------------------------------

    def to_next(self, u: Any) -> Any:
        return self.bdd.let(self._prime_f, u)

    def to_cur(self, u: Any) -> Any:
        return self.bdd.let(self._unprime_f, u)

    def cpre(self, X: Any) -> Any:
        """Controllable predecessor of §3.4 (dead ends never belong to it)."""
        b = self.bdd
        xn = self.to_next(X)
        env_bad = and_exists(b, self.tu, ~xn, self.nxt_vars)
        ctrl_good = and_exists(b, self.tc_own, xn, self.nxt_vars)
        return (self.env & ~env_bad) | ctrl_good

    def restrict(self, care: Any) -> None:
        """Restrict the game relations to ``care`` (e.g. the reachable states).

        Only sound for a forward-closed ``care`` (every successor of a care state is a care
        state): then no relevant edge is lost and no CPre result carries unreachable states.
        Measured on DoorPatrol_8: the restricted relations are larger (696/725 vs 280/385
        nodes) yet CPre costs the same either way, since the fixpoint's iterates are
        intersected with ``Z`` and dominate the relational products.  The controllable
        relation used by CPre is restricted to controller-owned sources, the only ones where
        it matters (§3.3).
        """
        cn = self.to_next(care)
        self.tu = self.tu & care & cn
        self.tc = self.tc & care & cn
        self.tc_own = self.tc & ~self.env
        self.t_any = self.t_any & care & cn

    def post(self, X: Any) -> Any:
        return self.to_cur(and_exists(self.bdd, self.t_any, X, self.cur_vars))

    def pre_any(self, X: Any) -> Any:
        return and_exists(self.bdd, self.t_any, self.to_next(X), self.nxt_vars)

    def reachable(self) -> Any:
        """Forward-reachable states from ``init`` (also cached as ``self.reach``)."""
        R = self.init
        frontier = self.init
        from iterplan_compiler import limits

        while frontier != self.bdd.false:
            limits.check_deadline()  # --time-limit between image steps
            img = self.post(frontier)
            frontier = img & ~R
            R |= frontier
        self.reach = R
        return R

    def count(self, u: Any) -> int:
        return int(self.bdd.count(u, nvars=len(self.cur_vars))) if u != self.bdd.false else 0

    def decode(self, assignment: dict[str, bool], vecs: list[BitVec]) -> tuple[int, ...]:
        return tuple(v.decode(assignment) for v in vecs)

    def state_cube(self, tup: tuple[int, ...]) -> Any:
        u = self.bdd.true
        for vec, val in zip(self.cur, tup, strict=True):
            u &= vec.eq(self.bdd, val)
        return u

    def successors(self, tup: tuple[int, ...]) -> list[tuple[str, tuple[int, ...] | None]]:
        """Explicit successors ``(label, next tuple or None for ERROR)`` of a state."""
        b = self.bdd
        u = self.trans & self.state_cube(tup)
        u = b.exist(self.cur_vars, u)
        care = self.act_vars | self.nxt_vars
        out = []
        for asg in b.pick_iter(u, care_vars=care):
            a = self.actions[self.act.decode(asg)]
            nt = self.decode(asg, self.nxt)
            is_err = any(e is not None and nt[k] == e for k, e in enumerate(self.err_code))
            out.append((a, None if is_err else nt))
        return sorted(set(out), key=lambda x: (x[0], x[1] or ()))

    def fluent_values(self, tup: tuple[int, ...]) -> dict[str, bool]:
        nbody = self.spec.num_plant + self.spec.num_safety
        return {name: tup[nbody + i] == 1 for i, name in enumerate(self.spec.fluent_names)}


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
        return [frozenset(s for s in range(n) if vals[s] is not None and inside[s]
                          and evaluate(f, vals[s])) for f in formulas]

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
                   explain: bool, name: str, order: str = "clustered",
                   permissive: bool = False) -> tuple[bool, LTS | None, str]:
    """Symbolic solve + MTSA controller extraction; returns (realizable, controller, why)."""
    t = time.perf_counter()
    g = SymbolicGame(spec, order=order)
    stats["bdd_backend"] = type(g.bdd).__module__
    stats["order"] = order
    stats["t_encode"] = time.perf_counter() - t
    t = time.perf_counter()
    reach = g.reachable()
    g.restrict(reach)
    stats["t_reach"] = time.perf_counter() - t
    live = reach & ~g.error
    stats["game_states"] = g.count(live) + (1 if (reach & g.error) != g.bdd.false else 0)
    stats["trans_bdd_nodes"] = len(g.trans)
    stats["bdd_vars"] = len(g.bdd.vars)
    say(f"symbolic game: {stats['game_states']} reachable states, |T| = {len(g.trans)} nodes")
    t = time.perf_counter()
    alphabet = spec.alphabet
    if spec.mode == "nonblocking":
        marked = g.guarantees[0] & reach
        W = nonblocking_symbolic(g, reach, marked)
        stats["t_solve"] = time.perf_counter() - t
        stats["winning_states"] = g.count(W)
        if (g.init & W) == g.bdd.false:
            return False, None, _explain_symbolic(g, reach, W, explain)
        t = time.perf_counter()
        game = subgame(g, W)
        region = frozenset(s for s in range(game.num_states) if game.inside[s])  # type: ignore[attr-defined]
        ctrl = extract_director(game, region, game.guarantees[0], name, alphabet)
        stats["t_extract"] = time.perf_counter() - t
        return True, ctrl, ""
    goals = [gj | g.failures for gj in (g.guarantees or [g.bdd.true & ~g.error])]
    fp = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=reach, must_contain=g.init,
                     progress=say)
    W = fp.winning & reach
    stats["t_solve"] = time.perf_counter() - t
    stats["fixpoint_iterations"] = fp.iterations
    stats["winning_bdd_nodes"] = len(W)
    if (g.init & W) == g.bdd.false:
        return False, None, _explain_symbolic(g, reach, W, explain)
    stats["winning_states"] = g.count(W)
    from iterplan_compiler import limits

    cap = limits.current().max_states
    if stats["winning_states"] > cap:  # the controller is extracted explicitly from W
        raise limits.LimitReached("max_states", limits.states_message(
            cap, f"the winning region of {name or 'the game'} ({stats['winning_states']:,} "
            "states, the controller's size)"))
    t = time.perf_counter()
    game = subgame(g, W, limit=cap)
    # H_j over the full reachable game, as MTSA computes it (§3.5)
    A = g.assumptions or [live]
    heights = []
    for gj in goals:
        heights.append(1 + max(g.count(a & live & ~gj) for a in A))
    ranks = solve_ranks(game, candidates=lambda s: game.inside[s],  # type: ignore[attr-defined]
                        heights=heights)
    if not ranks.winning(game.initial):  # pragma: no cover - would be a solver bug
        raise AssertionError("symbolic and rank solvers disagree on the initial state")
    ctrl = extract_controller(game, ranks, name, alphabet, permissive=permissive)
    stats["t_extract"] = time.perf_counter() - t
    return True, ctrl, ""


def _explain_symbolic(g: SymbolicGame, reach: Any, W: Any, explain: bool) -> str:
    losing = g.count(reach & ~W & ~g.error)
    head = (f"unrealizable: the initial state is losing ({losing} reachable non-ERROR game "
            f"states are losing)")
    if not explain:
        return head
    if g.count(reach) > 50_000:
        return head + "\n(game too large for a counter-strategy trace; try a smaller instance)"
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
