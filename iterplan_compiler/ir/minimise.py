"""Determinisation, minimisation and bisimulation on explicit LTSs.

* :func:`tau_closure` — states reachable by ``tau*`` (ERROR included as ``-1``).
* :func:`determinise` — tau elimination + subset construction (MTSA ``deterministic``'s first
  half).  A subset that contains ERROR *is* ERROR: once an error is possible along a trace the
  trace is an error trace (LTSA's convention for safety properties).
* :func:`minimise` — Hopcroft partition refinement of a deterministic LTS (partial transition
  function; the Valmari–Lehtinen variant that needs no completion sink).
* :func:`deterministic` — ``minimise(determinise(lts))``: MTSA's ``deterministic`` keyword.
* :func:`strong_minimise` — quotient by strong bisimulation.
* :func:`weak_minimise` — quotient by weak (observational) bisimulation; MTSA ``minimal``.
* :func:`bisimilar` — strong or weak bisimilarity of two LTSs.
* :func:`trace_difference` — a shortest trace where two LTSs differ (for error messages).

ERROR is treated everywhere as one distinguished state with no moves, never equivalent to a
real state (not even to STOP).  END states are distinguished from non-END states (END and STOP
differ under sequential composition).  Every result is renumbered canonically (BFS from the
initial state), so equal inputs give byte-identical outputs.
"""

from __future__ import annotations

from collections.abc import Sequence

from .alphabet_ops import NotDeterministic
from .lts import ERROR, LTS, TAU, make_lts, reachable

__all__ = [
    "bisimilar",
    "determinise",
    "deterministic",
    "minimise",
    "strong_minimise",
    "tau_closure",
    "trace_difference",
    "weak_minimise",
]


def _successors(lts: LTS) -> list[list[tuple[str, int]]]:
    out: list[list[tuple[str, int]]] = [[] for _ in range(lts.num_states)]
    for s, a, t in lts.transitions:
        out[s].append((a, t))
    return out


def tau_closure(lts: LTS) -> list[frozenset[int]]:
    """Return, for each state, the set of states reachable by zero or more tau moves.

    ERROR appears as ``-1`` in a closure when a tau path enters it.
    """
    tau_succ: list[list[int]] = [[] for _ in range(lts.num_states)]
    for s, a, t in lts.transitions:
        if a == TAU:
            tau_succ[s].append(t)
    closures: list[frozenset[int]] = []
    for s in range(lts.num_states):
        if not tau_succ[s]:
            closures.append(frozenset((s,)))
            continue
        seen = {s}
        stack = [s]
        while stack:
            u = stack.pop()
            if u == ERROR:
                continue
            for v in tau_succ[u]:
                if v not in seen:
                    seen.add(v)
                    stack.append(v)
        closures.append(frozenset(seen))
    return closures


def determinise(lts: LTS, name: str | None = None) -> LTS:
    """Tau-free deterministic LTS with the same traces (and error traces) as ``lts``.

    A subset state is END if it contains an END state.  A subset containing ERROR becomes
    ERROR.  Corner case: if ERROR is tau-reachable from the initial state (``P = ERROR``) the
    result keeps a single ``tau`` move from its initial state to ERROR, since an LTS cannot start
    in ERROR.  The alphabet is unchanged.
    """
    closure = tau_closure(lts)
    succ = _successors(lts)
    start = closure[lts.initial]
    if ERROR in start:
        return make_lts(name or lts.name, 1, [(0, TAU, ERROR)], lts.alphabet)
    index: dict[frozenset[int], int] = {start: 0}
    order: list[frozenset[int]] = [start]
    trans: list[tuple[int, str, int]] = []
    ends: list[int] = []
    head = 0
    while head < len(order):
        cur = order[head]
        src = head
        head += 1
        if not cur.isdisjoint(lts.end_states):
            ends.append(src)
        targets: dict[str, set[int]] = {}
        for s in cur:
            for a, t in succ[s]:
                if a == TAU:
                    continue
                bucket = targets.setdefault(a, set())
                if t == ERROR:
                    bucket.add(ERROR)
                else:
                    bucket |= closure[t]
        for a in sorted(targets):
            tgt = frozenset(targets[a])
            if ERROR in tgt:
                trans.append((src, a, ERROR))
                continue
            k = index.get(tgt)
            if k is None:
                k = len(order)
                index[tgt] = k
                order.append(tgt)
            trans.append((src, a, k))
    return make_lts(name or lts.name, len(order), trans, lts.alphabet, 0, ends)


def _initial_classes(lts: LTS) -> list[int]:
    """0 = ordinary state, 1 = END state (ERROR gets its own class separately)."""
    return [1 if s in lts.end_states else 0 for s in range(lts.num_states)]


def _quotient(lts: LTS, block: Sequence[int], error_block: int, name: str,
              drop_tau_loops: bool) -> LTS:
    """Build the quotient of ``lts`` under ``block`` (state -> block id) and renumber."""
    nb = max(block, default=-1) + 1
    nb = max(nb, error_block + 1)
    trans: set[tuple[int, str, int]] = set()
    for s, a, t in lts.transitions:
        b = block[s]
        c = error_block if t == ERROR else block[t]
        if drop_tau_loops and a == TAU and c == b:
            continue
        trans.add((b, a, ERROR if c == error_block else c))
    ends = {block[s] for s in lts.end_states}
    q = make_lts(name, nb, trans, lts.alphabet, block[lts.initial], ends)
    return reachable(q)


def minimise(lts: LTS, name: str | None = None) -> LTS:
    """Minimal deterministic LTS equivalent to a deterministic ``lts`` (Hopcroft).

    ``lts`` may contain tau moves but at most one move per (state, label) — tau is then an
    ordinary label.  Raises :class:`~iterplan_compiler.ir.alphabet_ops.NotDeterministic`
    otherwise.  For deterministic machines this is also the strong-bisimulation quotient.
    """
    n = lts.num_states
    err = n  # ERROR as an extra node without moves
    delta: dict[str, dict[int, int]] = {}
    for s, a, t in lts.transitions:
        row = delta.setdefault(a, {})
        if s in row:
            raise NotDeterministic(lts.name, s, a)
        row[s] = err if t == ERROR else t
    # Inverse transition function per label: target -> sources.
    inv: dict[str, dict[int, list[int]]] = {}
    for a, row in delta.items():
        ia: dict[int, list[int]] = {}
        for s, t in row.items():
            ia.setdefault(t, []).append(s)
        inv[a] = ia

    init = _initial_classes(lts)
    blocks: list[set[int]] = []
    block_of = [0] * (n + 1)
    for cls in (0, 1):
        members = {s for s in range(n) if init[s] == cls}
        if members:
            for s in members:
                block_of[s] = len(blocks)
            blocks.append(members)
    block_of[err] = len(blocks)
    blocks.append({err})

    labels = sorted(delta)
    # Partial DFA: every initial block must be a splitter for every label (no "skip largest").
    work: list[tuple[int, str]] = [(b, a) for b in range(len(blocks)) for a in labels]
    in_work = set(work)
    while work:
        splitter = work.pop()
        in_work.discard(splitter)
        b, a = splitter
        ia = inv[a]
        touched: dict[int, list[int]] = {}
        for t in list(blocks[b]):
            for s in ia.get(t, ()):
                touched.setdefault(block_of[s], []).append(s)
        for y in sorted(touched):
            xs = touched[y]
            if len(xs) == len(blocks[y]):
                continue
            part = set(xs)
            blocks[y] -= part
            z = len(blocks)
            blocks.append(part)
            for s in part:
                block_of[s] = z
            small = z if len(part) <= len(blocks[y]) else y
            for c in labels:
                if (y, c) in in_work:
                    entry = (z, c)
                else:
                    entry = (small, c)
                if entry not in in_work:
                    in_work.add(entry)
                    work.append(entry)
    return _quotient(lts, block_of[:n], block_of[err], name or lts.name, drop_tau_loops=False)


def deterministic(lts: LTS, name: str | None = None) -> LTS:
    """MTSA ``deterministic``: tau elimination, subset construction, minimisation."""
    return minimise(determinise(lts, name), name)


def _refine(succ: Sequence[Sequence[tuple[str, int]]], init: Sequence[int]) -> list[int]:
    """Coarsest partition refining ``init`` that is a bisimulation for ``succ``.

    Signature refinement with a dirty set.  A state's signature is the set of (label, block
    of target) pairs.  Invariant at the start of each round: all members of a block share one
    stored signature (``block_sig``).  Only predecessors of states that changed block are
    re-evaluated ("dirty"); in a touched block the clean members keep the block's id and only
    dirty states whose new signature differs move out, so the cost of a round is proportional
    to the dirty states, not to the block sizes (long chains stay near-linear).
    The coarsest partition is unique, so processing order does not affect the result; blocks
    are renumbered in first-seen state order at the end.
    """
    n = len(succ)
    preds: list[list[int]] = [[] for _ in range(n)]
    for s, moves in enumerate(succ):
        for _, t in moves:
            preds[t].append(s)
    ids: dict[int, int] = {}
    block = [ids.setdefault(c, len(ids)) for c in init]
    members: dict[int, set[int]] = {}
    for s, b in enumerate(block):
        members.setdefault(b, set()).add(s)
    Sig = frozenset[tuple[str, int]]
    block_sig: dict[int, Sig | None] = {b: None for b in members}
    next_id = len(ids)
    dirty: set[int] = set(range(n))
    while dirty:
        by_block: dict[int, dict[Sig, list[int]]] = {}
        for s in dirty:
            sg = frozenset((a, block[t]) for a, t in succ[s])
            by_block.setdefault(block[s], {}).setdefault(sg, []).append(s)
        dirty = set()
        for b, groups in by_block.items():
            old = block_sig[b]
            n_dirty = sum(len(g) for g in groups.values())
            clean = len(members[b]) - n_dirty
            if clean > 0 or old in groups:
                # The clean members (plus dirty ones that kept the old signature) stay in b.
                stay_sig = old
            else:
                # Every member is dirty and none kept the old signature: keep the largest group.
                stay_sig = max(groups, key=lambda g: (len(groups[g]), -min(groups[g])))
            block_sig[b] = stay_sig
            for sg, group in groups.items():
                if sg == stay_sig:
                    continue
                nb = next_id
                next_id += 1
                members[nb] = set(group)
                members[b].difference_update(group)
                block_sig[nb] = sg
                for s in group:
                    block[s] = nb
                    dirty.update(preds[s])
    renum: dict[int, int] = {}
    return [renum.setdefault(b, len(renum)) for b in block]


def _graph(lts: LTS, offset: int, err: int) -> list[list[tuple[str, int]]]:
    """Successor lists with states shifted by ``offset`` and ERROR mapped to node ``err``."""
    out: list[list[tuple[str, int]]] = [[] for _ in range(lts.num_states)]
    for s, a, t in lts.transitions:
        out[s].append((a, err if t == ERROR else t + offset))
    return out


def _weak_graph(lts: LTS, offset: int, err: int) -> list[list[tuple[str, int]]]:
    """Saturated successors: ``s =a=> u`` (tau* a tau*) and ``s =tau=> u`` (tau*, incl. s)."""
    closure = tau_closure(lts)
    succ = _successors(lts)

    def node(u: int) -> int:
        return err if u == ERROR else u + offset

    out: list[list[tuple[str, int]]] = []
    for s in range(lts.num_states):
        moves: set[tuple[str, int]] = {(TAU, node(u)) for u in closure[s]}
        for u in closure[s]:
            if u == ERROR:
                continue
            for a, t in succ[u]:
                if a == TAU:
                    continue
                if t == ERROR:
                    moves.add((a, err))
                else:
                    moves.update((a, node(v)) for v in closure[t])
        out.append(sorted(moves))
    return out


def strong_minimise(lts: LTS, name: str | None = None) -> LTS:
    """Quotient of ``lts`` by strong bisimulation (tau is an ordinary label)."""
    n = lts.num_states
    succ = _graph(lts, 0, n) + [[]]
    init = [*_initial_classes(lts), 2]
    block = _refine(succ, init)
    return _quotient(lts, block[:n], block[n], name or lts.name, drop_tau_loops=False)


def weak_minimise(lts: LTS, name: str | None = None) -> LTS:
    """Quotient of ``lts`` by weak bisimulation (MTSA ``minimal``).

    Quotient moves are the original moves between blocks, minus tau self-loops of a block, so
    the result is weakly bisimilar to ``lts``.  Divergence (tau cycles) is not preserved.
    """
    n = lts.num_states
    succ = _weak_graph(lts, 0, n) + [[(TAU, n)]]
    init = [*_initial_classes(lts), 2]
    block = _refine(succ, init)
    return _quotient(lts, block[:n], block[n], name or lts.name, drop_tau_loops=True)


def bisimilar(a: LTS, b: LTS, weak: bool = False, *, same_alphabet: bool = True) -> bool:
    """True iff the initial states of ``a`` and ``b`` are (strongly / weakly) bisimilar.

    With ``same_alphabet`` (default) machines with different alphabets are never bisimilar,
    because they behave differently in a composition.  ERROR is one shared distinguished
    state; END states are distinguished from other states.
    """
    if same_alphabet and a.alphabet != b.alphabet:
        return False
    na, nb = a.num_states, b.num_states
    err = na + nb
    build = _weak_graph if weak else _graph
    succ = build(a, 0, err) + build(b, na, err)
    succ.append([(TAU, err)] if weak else [])
    init = [*_initial_classes(a), *_initial_classes(b), 2]
    block = _refine(succ, init)
    return block[a.initial] == block[na + b.initial]


def trace_difference(a: LTS, b: LTS) -> tuple[tuple[str, ...], frozenset[str], frozenset[str]] | None:
    """A shortest trace after which ``a`` and ``b`` offer different visible moves, or None.

    Works on the determinised machines, so it finds *trace* differences (None for
    trace-equivalent machines, even if they are not bisimilar).  An offer is a label ``x``, or
    ``x->ERROR`` when the move enters ERROR, or ``END``.  The result ``(trace, only_a,
    only_b)`` is meant for messages ("after [x, y] ExpectedC offers {z} but C does not").
    """
    da, db = determinise(a), determinise(b)
    sa, sb = _successors(da), _successors(db)

    def offers(m: LTS, succ: list[list[tuple[str, int]]], s: int) -> set[str]:
        out = {x if t != ERROR else f"{x}->ERROR" for x, t in succ[s]}
        if s in m.end_states:
            out.add("END")
        return out

    start = (da.initial, db.initial)
    parent: dict[tuple[int, int], tuple[tuple[int, int], str] | None] = {start: None}
    queue = [start]
    head = 0
    while head < len(queue):
        pa, pb = queue[head]
        head += 1
        oa, ob = offers(da, sa, pa), offers(db, sb, pb)
        if oa != ob:
            trace: list[str] = []
            step = parent[(pa, pb)]
            while step is not None:
                prev, lab = step
                trace.append(lab)
                step = parent[prev]
            trace.reverse()
            return tuple(trace), frozenset(oa - ob), frozenset(ob - oa)
        succ_b = dict(sb[pb])
        for x, ta in sorted(sa[pa]):
            tb = succ_b[x]
            if ta == ERROR or tb == ERROR:
                continue
            nxt = (ta, tb)
            if nxt not in parent:
                parent[nxt] = ((pa, pb), x)
                queue.append(nxt)
    return None
