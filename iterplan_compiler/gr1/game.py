"""Boolean-variable GR(1) games with slugs semantics, built as BDDs.

A :class:`Game` is built from a :class:`~iterplan_compiler.gr1.slugsin.SlugsSpec` into a
caller-supplied ``dd`` manager (never a module-global one).  Semantics (slugs, Ehlers &
Raman CAV'16):

* variables: inputs ``x`` (environment) and outputs ``y`` (system), each with a primed copy;
* the system is *Mealy*: it picks ``y'`` after seeing ``x'``;
* ``ENV_TRANS`` ranges over ``x, y, x'``; ``SYS_TRANS`` over ``x, y, x', y'``;
* liveness lines may mention primed variables (transition-based justice);
* initial condition ``∀x. θe → ∃y. θs ∧ Win``.

Design choices (all measurable, see ``docs/gr1.md``):

* **Variable order** (:class:`GameOrder`) — ``INTERLEAVED`` (default; slugs' choice: each bit
  next to its primed copy, in declaration order), ``BLOCKED`` (gr1c's: all current bits, then
  all primed bits) or ``SPEC`` (interleaved, in order of first occurrence, :func:`spec_order`).  ``group_pairs`` ties each ``(v, v')`` pair into a CUDD reordering group so
  sifting moves them together (Spectra's "reorder with grouping").
* **Partitioned transition relations** — every TRANS line is one conjunct; consecutive
  conjuncts are clustered up to ``cluster_nodes`` BDD nodes and each cluster carries the
  primed variables that no later cluster mentions, so the controllable predecessor
  quantifies them as early as possible (fused ``and_exists`` / ``or_forall`` of CUDD).
"""

from __future__ import annotations

import enum
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

from iterplan_compiler.diagnostics import Diagnostic, error
from iterplan_compiler.gr1.slugsin import Expr, SlugsSpec, variables_of
from iterplan_compiler.symbolic import bdd as _bdd
from iterplan_compiler.symbolic.backoff import Backoff
from iterplan_compiler.symbolic.backoff import install as install_backoff

Node = Any

def prime_name(name: str) -> str:
    """Name of the primed (next-state) BDD variable of ``name``."""
    return name + "'"


class GameOrder(enum.Enum):
    """Initial BDD variable order of a game (``iterc solve --order``)."""

    INTERLEAVED = "interleaved"   # each bit next to its primed copy, in declaration order
    BLOCKED = "blocked"           # all current bits, then all primed bits
    SPEC = "spec"                 # interleaved, in order of first occurrence (spec_order)


@dataclass(frozen=True)
class GameOptions:
    """How to build the BDDs of a game.

    ``order``: a :class:`GameOrder`;
    ``group_pairs``: CUDD reordering groups for ``(v, v')`` (interleaved order only);
    ``reordering``: CUDD dynamic reordering (group sifting, the only method dd exposes);
    ``sift_after_build``: with ``reordering``, one explicit sifting pass once the
    partitioned relations exist (see :func:`build_game`); ``max_growth``: CUDD's sifting
    growth bound;
    ``partition``: keep the transition relations as quantification-scheduled clusters
    (otherwise one monolithic BDD per player); ``cluster_nodes``: cluster size bound;
    ``reorder_backoff``: with ``reordering``, CUDD's trigger backs off inside a fused product
    that keeps restarting (:mod:`iterplan_compiler.symbolic.backoff`).
    """

    order: GameOrder = GameOrder.INTERLEAVED
    group_pairs: bool = False
    reordering: bool = True
    sift_after_build: bool = True
    max_growth: float | None = None
    partition: bool = True
    cluster_nodes: int = 5000
    reorder_backoff: bool = True


@dataclass
class Part:
    """One cluster of a partitioned transition relation and the primed variables that may be
    quantified right after conjoining it (no later cluster mentions them)."""

    bdd: Node
    qvars: frozenset[str]


@dataclass
class Game:
    """A GR(1) game over Boolean variables (see the module docstring for the semantics)."""

    bdd: Any
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    env_init: Node
    sys_init: Node
    env_trans_lines: list[Node]
    sys_trans_lines: list[Node]
    env_parts: list[Part]
    sys_parts: list[Part]
    env_pre_q: frozenset[str]
    sys_pre_q: frozenset[str]
    env_live: list[Node]
    sys_live: list[Node]
    live_primed: bool
    options: GameOptions
    stats: dict[str, Any] = field(default_factory=dict)
    backoff: Backoff | None = None  # the manager's restart back-off (symbolic/backoff.py)

    _mono: dict[str, Node] = field(default_factory=dict)
    _swap_map: dict[str, str] | None = None
    _is_cudd: bool = False

    @property
    def env_trans(self) -> Node:
        """Monolithic ``ρe`` (built on first use; partitioned runs may never need it)."""
        if "env" not in self._mono:
            self._mono["env"] = _all_of(self.bdd, self.env_trans_lines)
        return self._mono["env"]

    @property
    def sys_trans(self) -> Node:
        """Monolithic ``ρs`` (built on first use)."""
        if "sys" not in self._mono:
            self._mono["sys"] = _all_of(self.bdd, self.sys_trans_lines)
        return self._mono["sys"]

    # --- variable sets -------------------------------------------------------------------
    @property
    def x(self) -> tuple[str, ...]:
        return self.inputs

    @property
    def y(self) -> tuple[str, ...]:
        return self.outputs

    @property
    def xp(self) -> tuple[str, ...]:
        return tuple(prime_name(v) for v in self.inputs)

    @property
    def yp(self) -> tuple[str, ...]:
        return tuple(prime_name(v) for v in self.outputs)

    # --- operators -------------------------------------------------------------------------
    def prime(self, u: Node) -> Node:
        """Rename a *state* predicate (current variables only) to the next-state copy."""
        if self._swap_map is None:
            self._swap_map = {v: prime_name(v) for v in self.inputs + self.outputs}
            self._is_cudd = _bdd.backend_of(self.bdd) == "cudd"
        if self._is_cudd:
            # CUDD's variable swap is much cheaper than vector composition; it is exact
            # because ``u`` mentions no primed variable.
            return self.bdd._swap(u, self._swap_map)
        return self.bdd.let({v: self.bdd.var(p) for v, p in self._swap_map.items()}, u)

    def and_exists(self, u: Node, v: Node, qvars: Iterable[str]) -> Node:
        """``∃ qvars. u ∧ v`` (fused in CUDD; :func:`symbolic.bdd.and_exists`)."""
        return _bdd.and_exists(self.bdd, u, v, qvars, self.backoff)

    def or_forall(self, u: Node, v: Node, qvars: Iterable[str]) -> Node:
        """``∀ qvars. u ∨ v`` (fused in CUDD; :func:`symbolic.bdd.or_forall`)."""
        return _bdd.or_forall(self.bdd, u, v, qvars, self.backoff)

    def cpre_trans(self, target: Node) -> Node:
        """Mealy controllable predecessor of a transition-level target.

        ``∀x'. (ρe → ∃y'. (ρs ∧ target))``: the current states from which, for every legal
        next input, the system has a legal next output such that the transition satisfies
        ``target`` (which may mention current and next variables).
        """
        if self.options.partition:
            s = self.sys_image(target)
            if self.env_pre_q:
                s = self.bdd.forall(set(self.env_pre_q), s)
            for p in self.env_parts:
                s = self.or_forall(~p.bdd, s, p.qvars)
            return s
        s = self.and_exists(self.sys_trans, target, self.yp)
        return self.or_forall(~self.env_trans, s, self.xp)

    def sys_image(self, target: Node) -> Node:
        """``∃y'. (ρs ∧ target)`` — the system half of the controllable predecessor."""
        if not self.options.partition:
            return self.and_exists(self.sys_trans, target, self.yp)
        s = target
        if self.sys_pre_q:
            s = self.bdd.exist(set(self.sys_pre_q), s)
        for p in self.sys_parts:
            s = self.and_exists(s, p.bdd, p.qvars)
        return s

    def cpre(self, states: Node) -> Node:
        """Controllable predecessor of a *state* set (``cpre_trans`` of its primed copy)."""
        return self.cpre_trans(self.prime(states))

    def initial_ok(self, win: Node) -> bool:
        """slugs' initial condition ``∀x. θe → ∃y. (θs ∧ win)`` (free leftovers universal)."""
        bdd = self.bdd
        inner = bdd.exist(set(self.outputs), self.sys_init & win)
        u = self.or_forall(~self.env_init, inner, self.inputs)
        rest = bdd.support(u)
        if rest:
            u = bdd.forall(rest, u)
        return u == bdd.true

    def node_count(self, nodes: Sequence[Node]) -> int:
        """Shared DAG size of ``nodes`` (dd.cudd), else the sum of sizes."""
        try:
            from dd.cudd import count_nodes

            return int(count_nodes(list(nodes)))
        except Exception:  # autoref or empty list
            return sum(len(n) for n in nodes)


def _all_of(bdd: Any, us: Sequence[Node]) -> Node:
    r = bdd.true
    for u in us:
        r &= u
    return r


# --- building ----------------------------------------------------------------------------


def _build_expr(bdd: Any, expr: Expr, memo: dict[int, Node]) -> Node:
    """BDD of ``expr``; iterative post-order (prefix formulas can nest very deeply) with a
    memo keyed by node identity so ``$``/``?`` shared sub-formulas are built once."""
    stack: list[tuple[Expr, bool]] = [(expr, False)]
    while stack:
        e, done = stack.pop()
        key = id(e)
        if key in memo:
            continue
        if e.op == "const":
            memo[key] = bdd.true if e.value else bdd.false
        elif e.op == "var":
            memo[key] = bdd.var(prime_name(e.name) if e.primed else e.name)
        elif not done:
            stack.append((e, True))
            stack.extend((a, False) for a in e.args if id(a) not in memo)
        else:
            vals = [memo[id(a)] for a in e.args]
            if e.op == "not":
                memo[key] = ~vals[0]
            elif e.op == "and":
                memo[key] = vals[0] & vals[1]
            elif e.op == "or":
                memo[key] = vals[0] | vals[1]
            else:  # xor
                memo[key] = ~vals[0].equiv(vals[1])
    return memo[id(expr)]


def spec_order(spec: SlugsSpec) -> list[str]:
    """Variables in order of first occurrence in the spec's formulas (TRANS, then LIVENESS,
    then INIT lines; left-to-right within a line), then any unused declared ones.

    Variables that one transition line relates end up next to each other, which is what
    keeps a conjunct's BDD small: with declaration order (all inputs, then all outputs) a
    line family like ``b_i ∧ f_i → ¬b_i'`` (gr1c's lift) makes the conjunction of the lines
    exponential in ``n`` until sifting repairs it.
    """
    seen: dict[str, None] = {}
    for sec in ("ENV_TRANS", "SYS_TRANS", "ENV_LIVENESS", "SYS_LIVENESS", "ENV_INIT",
                "SYS_INIT"):
        for line in spec.lines(sec):
            visited: set[int] = set()
            stack = [line.expr]
            while stack:
                e = stack.pop()
                if id(e) in visited:
                    continue
                visited.add(id(e))
                if e.op == "var":
                    seen.setdefault(e.name, None)
                else:
                    stack.extend(reversed(e.args))
    for v in list(spec.inputs) + list(spec.outputs):
        seen.setdefault(v, None)
    return list(seen)


def _declare(bdd: Any, names: Sequence[str], options: GameOptions) -> None:
    if options.order is GameOrder.BLOCKED:
        bdd.declare(*names)
        bdd.declare(*(prime_name(v) for v in names))
        return
    for v in names:
        bdd.declare(v, prime_name(v))
    if options.group_pairs and hasattr(bdd, "group"):
        bdd.group({v: 2 for v in names})


def _schedule(game_bdd: Any, parts: list[Node], qvars: Sequence[str], limit: int,
              support_of, precheck: bool = False) -> tuple[list[Part], frozenset[str]]:
    """Cluster ``parts`` (in order) up to ``limit`` nodes; attach early-quantifiable vars.

    ``precheck``: do not even try a conjunction whose operands together exceed ``limit``
    (re-clustering big clusters would otherwise conjoin them just to reject the result)."""
    clusters: list[Node] = []
    cur = None
    for p in parts:
        if p == game_bdd.true:
            continue
        if cur is None:
            cur = p
            continue
        cand = None if precheck and len(cur) + len(p) > limit else cur & p
        if cand is not None and len(cand) <= limit:
            cur = cand
        else:
            clusters.append(cur)
            cur = p
    if cur is not None:
        clusters.append(cur)
    q = set(qvars)
    supports = [support_of(c) & q for c in clusters]
    mentioned = set().union(*supports) if supports else set()
    pre_q = frozenset(q - mentioned)
    out: list[Part] = []
    later: set[str] = set()
    last_q: list[frozenset[str]] = [frozenset()] * len(clusters)
    for k in range(len(clusters) - 1, -1, -1):
        last_q[k] = frozenset(supports[k] - later)
        later |= supports[k]
    for c, lq in zip(clusters, last_q, strict=True):
        out.append(Part(c, lq))
    return out, pre_q


def _recluster(bdd: Any, parts: list[Part], pre_q: frozenset[str], qvars: Sequence[str],
               options: GameOptions, support_of: Any) -> tuple[list[Part], frozenset[str]]:
    """:func:`_schedule` again over existing clusters (same conjunction; a variable that
    dropped out of every support joins the up-front quantified ones)."""
    new_parts, new_pre = _schedule(bdd, [p.bdd for p in parts], qvars, options.cluster_nodes,
                                   support_of, precheck=True)
    return new_parts, pre_q | new_pre


def _sift_after_build(bdd: Any, options: GameOptions, support_of: Any, xp: Sequence[str],
                      yp: Sequence[str],
                      parts: tuple[list[Part], frozenset[str], list[Part], frozenset[str]]
                      ) -> tuple[list[Part], frozenset[str], list[Part], frozenset[str]]:
    """One explicit sifting pass with the partitioned relations alive, then re-clustering.

    Dynamic sifting during the build optimises the order for whatever is alive at the
    time (single lines, partial formulas), and every reordering raises CUDD's next trigger
    threshold, so the small fixpoint BDDs may never trigger a repair.  One pass now, with
    exactly the relations the fixpoint uses alive, adapts the order to them: gr1c's lift
    n=50 went from > 100 s to ~2 s CPU (its environment lines b_i ∧ f_i → ¬b_i' had been
    cut into 13 k-node clusters; after the pass they conjoin to one of ~1 k nodes).  The
    clusters were cut at ``cluster_nodes`` under the old order, so they are scheduled again.
    """
    env_parts, env_pre, sys_parts, sys_pre = parts
    bdd.reorder()
    if options.partition:
        env_parts, env_pre = _recluster(bdd, env_parts, env_pre, xp, options, support_of)
        sys_parts, sys_pre = _recluster(bdd, sys_parts, sys_pre, yp, options, support_of)
    return env_parts, env_pre, sys_parts, sys_pre


def _check_primes(spec: SlugsSpec) -> list[Diagnostic]:
    """``G201`` for a primed variable in an INIT section, ``G202`` for a primed output in
    ENV_TRANS (in spec order)."""
    diags: list[Diagnostic] = []
    for sec in ("ENV_INIT", "SYS_INIT"):
        for line in spec.lines(sec):
            if any(p for _, p in variables_of(line.expr)):
                diags.append(error("G201", f"[{sec}] formulas may not mention primed "
                                   "variables", line.span))
    outs = set(spec.outputs)
    for line in spec.lines("ENV_TRANS"):
        bad = sorted(prime_name(n) for n, p in variables_of(line.expr) if p and n in outs)
        if bad:
            diags.append(error("G202", "[ENV_TRANS] may not mention next-state outputs "
                               f"({', '.join(bad)})", line.span))
    return diags


def build_game(spec: SlugsSpec, bdd: Any, options: GameOptions | None = None
               ) -> tuple[Game | None, list[Diagnostic]]:
    """Build the BDDs of ``spec`` into the (fresh) manager ``bdd``.

    Diagnostics: ``G201`` primed variable in an INIT section, ``G202`` ENV_TRANS mentions a
    primed output (the environment cannot see the system's next move in slugs semantics).
    """
    options = options or GameOptions()
    diags = _check_primes(spec)
    if diags:
        return None, diags

    cfg: dict[str, Any] = {"reordering": options.reordering}
    if options.max_growth is not None:
        cfg["max_growth"] = options.max_growth
    bdd.configure(**cfg)
    backoff = install_backoff(bdd) if options.reordering and options.reorder_backoff else None
    names = (spec_order(spec) if options.order is GameOrder.SPEC
             else list(spec.inputs) + list(spec.outputs))
    _declare(bdd, names, options)

    memo: dict[int, Node] = {}

    def conj(sec: str) -> list[Node]:
        return [_build_expr(bdd, line.expr, memo) for line in spec.lines(sec)]

    env_init_l, sys_init_l = conj("ENV_INIT"), conj("SYS_INIT")
    env_trans_l, sys_trans_l = conj("ENV_TRANS"), conj("SYS_TRANS")
    env_live = conj("ENV_LIVENESS") or [bdd.true]
    sys_live = conj("SYS_LIVENESS") or [bdd.true]
    memo.clear()  # drop references to intermediate sub-formulas

    def support_of(u: Node) -> set[str]:
        return set(bdd.support(u))

    xp = [prime_name(v) for v in spec.inputs]
    yp = [prime_name(v) for v in spec.outputs]
    if options.partition:
        env_parts, env_pre = _schedule(bdd, env_trans_l, xp, options.cluster_nodes, support_of)
        sys_parts, sys_pre = _schedule(bdd, sys_trans_l, yp, options.cluster_nodes, support_of)
    else:
        env_parts, env_pre, sys_parts, sys_pre = [], frozenset(), [], frozenset()
    if options.reordering and options.sift_after_build:
        env_parts, env_pre, sys_parts, sys_pre = _sift_after_build(
            bdd, options, support_of, xp, yp, (env_parts, env_pre, sys_parts, sys_pre))
    primed = set(xp) | set(yp)
    live_primed = any(support_of(u) & primed for u in env_live + sys_live)
    game = Game(
        bdd=bdd,
        inputs=tuple(spec.inputs),
        outputs=tuple(spec.outputs),
        env_init=_all_of(bdd, env_init_l),
        sys_init=_all_of(bdd, sys_init_l),
        env_trans_lines=env_trans_l,
        sys_trans_lines=sys_trans_l,
        env_parts=env_parts,
        sys_parts=sys_parts,
        env_pre_q=env_pre,
        sys_pre_q=sys_pre,
        env_live=env_live,
        sys_live=sys_live,
        live_primed=live_primed,
        options=options,
        backoff=backoff,
    )
    game.stats.update(
        env_trans_nodes=game.node_count([p.bdd for p in env_parts]) if env_parts
        else len(game.env_trans),
        sys_trans_nodes=game.node_count([p.bdd for p in sys_parts]) if sys_parts
        else len(game.sys_trans),
        env_clusters=len(env_parts),
        sys_clusters=len(sys_parts),
        variables=2 * (len(spec.inputs) + len(spec.outputs)),
    )
    return game, diags
