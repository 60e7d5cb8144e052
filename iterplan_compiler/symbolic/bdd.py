"""BDD manager factory and bit-vector helpers over ``dd``'s common API.

Contract:

* :func:`new_manager` returns a fresh ``dd.cudd.BDD`` when CUDD bindings are importable, else a
  ``dd.autoref.BDD``; every other function here (and all of synthesis) uses only the interface
  both share (``declare``, ``var``, ``true``/``false``, ``&``/``|``/``~``, ``exist``, ``let``,
  ``count``, ``pick_iter``, ``reorder``, ``configure``, ``vars``), so one code path serves both.
  The manager is always passed explicitly — there is no module-level manager.
* :class:`BitVec` is an unsigned integer encoded in ``width`` named BDD variables (LSB first);
  :func:`declare_interleaved` declares current/next copies so that bit *k* of a vector and its
  primed copy are adjacent in the variable order (the usual choice for transition relations).
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from iterplan_compiler.symbolic.backoff import Backoff

Node = Any  # a dd BDD node (dd.cudd.Function or dd.autoref.Function)
Manager = Any


def _import_dd_cudd() -> Any:
    """``dd.cudd``, imported without networkx: ``dd._utils`` imports networkx (optional, for
    graph export, which iterplan never uses) and that import is 0.1-0.3 s of every ``iterc``
    run that synthesises.  A ``None`` entry in ``sys.modules`` makes dd's ``import networkx``
    fail, which dd handles; the entry is removed again, so later imports of networkx work."""
    blocked = "networkx" not in sys.modules
    if blocked:
        sys.modules["networkx"] = None  # type: ignore[assignment]
    try:
        import dd.cudd

        return dd.cudd
    finally:
        if blocked:
            del sys.modules["networkx"]


try:  # pragma: no cover - which branch runs depends on the installation
    _cudd = _import_dd_cudd()

    BACKEND = "cudd"
except ImportError:  # pragma: no cover
    _cudd = None
    BACKEND = "autoref"


def new_manager(*, backend: str | None = None, reordering: bool = False) -> Manager:
    """Return a new BDD manager (``backend``: ``"cudd"``, ``"autoref"`` or None = best).

    Dynamic reordering is off by default: synthesis declares a deliberate interleaved order
    and measured runs are reproducible only with a fixed order.
    """
    name = backend or BACKEND
    if name == "cudd":
        if _cudd is None:
            raise ImportError("dd.cudd is not available")
        # dd's defaults, kept on purpose (measured on GyroLTL_637/_700 up to the verdict,
        # `benchmarks/cudd_settings.py`, docs/synthesis.md "CUDD manager settings"):
        # * computed table 2^18 entries initially: CUDD doubles it by itself while the hit
        #   rate is above `min_hit` (30 %; 637 runs at 64 %) and it has at most twice the
        #   unique table's slots, so 637's reaches 2^23 (256 MB) anyway; a fixed 2^24 cut the
        #   cache insertions by 15 % but was 12-19 % *slower* (memory traffic), a capped 2^20-
        #   2^22 17-69 % slower (recomputation), and a big initial table costs every small
        #   problem its allocation (2^22: 50 ms, 120 MB);
        # * `min_hit` lower: identical counters (the hit rate is far above 30 %);
        # * garbage collection on: off was 21 % slower (5 collections, ~2 s, are cheaper than
        #   a unique table twice as large) and doubles the memory;
        # * memory estimate 1 GiB: CUDD collects at every unique-table growth once its memory
        #   passes 0.9 of it (a 2^25-entry cache does: no verdict in 200 s); 637's manager
        #   stays at ~480 MB through the director, and `loose_up_to` (6.7 M slots) is never
        #   reached (2.4 M).  Raise the estimate together with any larger cache;
        # * not a manager setting: huge pages for CUDD's tables (glibc's `hugetlb` tunable,
        #   read only at process start-up) gave ~7 % (median of 12 pairs), not taken.
        bdd = _cudd.BDD()
    else:
        import dd.autoref as _autoref

        bdd = _autoref.BDD()
    bdd.configure(reordering=reordering)
    return bdd


def backend_of(bdd: Manager) -> str:
    """Name of the library behind ``bdd`` (``"cudd"`` or ``"autoref"``)."""
    return "cudd" if type(bdd).__module__.startswith("dd.cudd") else "autoref"


def and_exists(bdd: Manager, u: Node, v: Node, qvars: Iterable[str],
               backoff: Backoff | None = None) -> Node:
    """``∃ qvars. u ∧ v`` — CUDD's fused relational product when available (bracketed for
    ``backoff``, the manager's :class:`~iterplan_compiler.symbolic.backoff.Backoff`)."""
    qv = set(qvars)
    if not qv:
        return u & v
    if _cudd is not None and backend_of(bdd) == "cudd":
        return _fused(_cudd.and_exists, u, v, qv, backoff)
    return bdd.exist(qv, u & v)


def _fused(op: Any, u: Node, v: Node, qv: set[str], backoff: Backoff | None) -> Node:
    """CUDD's fused ``op(u, v, qv)``, bracketed as one product for ``backoff``."""
    if backoff is None:
        return op(u, v, qv)
    backoff.enter()
    try:
        return op(u, v, qv)
    finally:
        backoff.leave()


def cofactor(bdd: Manager, u: Node, care: Node) -> Node:
    """A function equal to ``u`` on ``care`` (values outside are unspecified), usually with
    fewer nodes: CUDD's generalised cofactor ``Cudd_bddRestrict``; ``u`` itself elsewhere."""
    if _cudd is not None and backend_of(bdd) == "cudd":
        return _cudd.restrict(u, care)
    return u


def or_forall(bdd: Manager, u: Node, v: Node, qvars: Iterable[str],
              backoff: Backoff | None = None) -> Node:
    """``∀ qvars. u ∨ v`` — CUDD's fused operator when available (dual of :func:`and_exists`)."""
    qv = set(qvars)
    if not qv:
        return u | v
    if _cudd is not None and backend_of(bdd) == "cudd":
        return _fused(_cudd.or_forall, u, v, qv, backoff)
    return bdd.forall(qv, u | v)


def bits_for(n: int) -> int:
    """Number of bits needed to encode the values ``0 .. n-1`` (at least 1)."""
    return max(1, (max(n, 1) - 1).bit_length())


@dataclass(frozen=True)
class BitVec:
    """An unsigned integer stored in BDD variables ``names`` (least significant bit first)."""

    names: tuple[str, ...]

    @property
    def width(self) -> int:
        return len(self.names)

    def eq(self, bdd: Manager, value: int) -> Node:
        """BDD of ``self == value`` (``value`` must fit in ``width`` bits)."""
        if value < 0 or value >= (1 << self.width):
            raise ValueError(f"{value} does not fit in {self.width} bits")
        return bdd.cube(self.assign(value))

    def assign(self, value: int) -> dict[str, bool]:
        """The variable assignment encoding ``value``."""
        return {name: bool((value >> k) & 1) for k, name in enumerate(self.names)}

    def decode(self, assignment: dict[str, bool]) -> int:
        """Integer value of this vector in a (full enough) assignment; missing bits read 0."""
        return sum(1 << k for k, name in enumerate(self.names) if assignment.get(name, False))

    def less_than(self, bdd: Manager, bound: int) -> Node:
        """BDD of ``self < bound`` (used to exclude unused codes)."""
        if bound >= (1 << self.width):
            return bdd.true
        if bound <= 0:
            return bdd.false
        # Build from the most significant bit down: x < b iff at the first differing bit x has 0.
        u = bdd.false
        eq = bdd.true
        for k in reversed(range(self.width)):
            v = bdd.var(self.names[k])
            if (bound >> k) & 1:
                u |= eq & ~v
                eq &= v
            else:
                eq &= ~v
        return u

    def equal_to(self, bdd: Manager, other: BitVec) -> Node:
        """BDD of ``self == other`` (same width)."""
        if other.width != self.width:
            raise ValueError("width mismatch")
        u = bdd.true
        for a, b in zip(self.names, other.names, strict=True):
            u &= bdd.var(a).equiv(bdd.var(b))
        return u


def value_cubes(bdd: Manager, vec: BitVec, n: int) -> list[Node]:
    """``[vec.eq(bdd, v) for v in range(n)]``, computed with shared prefixes.

    Cubes of the values that agree on their low ``k`` bits share the conjunction of those
    literals, so all ``n`` cubes cost about ``2·2^width`` conjunctions instead of
    ``n·width`` — the difference matters when encoding a machine with 10^4+ states.
    """
    if n <= 0:
        return []
    if n > (1 << vec.width):
        raise ValueError(f"{n} values do not fit in {vec.width} bits")
    layer = [bdd.true]  # layer[v] for v < 2^k: conjunction of the low k bits of v
    for k, name in enumerate(vec.names):
        pos = bdd.var(name)
        neg = ~pos
        # value v = low + (bit << k); keep only prefixes some value below n still uses
        layer = [layer[v & ((1 << k) - 1)] & (pos if (v >> k) & 1 else neg)
                 for v in range(min(n, 1 << (k + 1)))]
    return layer[:n]


def declare_interleaved(bdd: Manager, prefix: str, width: int) -> tuple[BitVec, BitVec]:
    """Declare ``prefix_k`` and ``prefix_k'`` for k < width, interleaved; return (cur, nxt)."""
    cur = tuple(f"{prefix}_{k}" for k in range(width))
    nxt = tuple(f"{prefix}_{k}'" for k in range(width))
    for a, b in zip(cur, nxt, strict=True):
        bdd.declare(a, b)
    return BitVec(cur), BitVec(nxt)


def declare_plain(bdd: Manager, prefix: str, width: int) -> BitVec:
    """Declare an unprimed vector ``prefix_k`` (for values that are not part of the state)."""
    names = tuple(f"{prefix}_{k}" for k in range(width))
    bdd.declare(*names)
    return BitVec(names)


def enumerate_values(bdd: Manager, u: Node, vec: BitVec) -> list[int]:
    """Sorted integer values of ``vec`` in the set ``u`` (``u`` may mention other variables)."""
    others = set(bdd.support(u)) - set(vec.names)
    proj = bdd.exist(others, u) if others else u
    out = {vec.decode(a) for a in bdd.pick_iter(proj, care_vars=set(vec.names))}
    return sorted(out)


def disjoin(bdd: Manager, nodes: Sequence[Node]) -> Node:
    """OR of ``nodes`` by balanced pairwise reduction.

    Folding left-to-right ORs every small term into one ever-growing BDD (quadratic work);
    a balanced tree keeps the operands of similar size.
    """
    layer = list(nodes)
    if not layer:
        return bdd.false
    while len(layer) > 1:
        nxt = [layer[i] | layer[i + 1] for i in range(0, len(layer) - 1, 2)]
        if len(layer) % 2:
            nxt.append(layer[-1])
        layer = nxt
    return layer[0]


def cube(bdd: Manager, assignment: dict[str, bool]) -> Node:
    """Conjunction of literals."""
    u = bdd.true
    for name, val in assignment.items():
        v = bdd.var(name)
        u &= v if val else ~v
    return u


def count_nodes(nodes: Sequence[Node]) -> int:
    """Total number of distinct BDD nodes of ``nodes`` (shared nodes counted once, approx.)."""
    return sum(len(n) for n in nodes)
