"""Parametric GR(1) benchmark families, written from the published specifications, as slugsin.

Usage::

    python benchmarks/gr1/generators.py FAMILY N [-o FILE]
    python benchmarks/gr1/generators.py --list

Families (n = parameter):

* ``arbiter`` — Piterman, Pnueli, Sa'ar (VMCAI'06) arbiter: n request/grant pairs.
* ``lift`` — PPS06 lift controller with n floors (one-hot floors, ``up``/``sb`` outputs).
* ``lift_gr1c`` — the same lift as gr1c's example generator formulates it (no helper
  outputs; the formulation of the gr1c anchor numbers).
* ``genbuf`` — Bloem et al. generalized buffer: n senders, 2 receivers, FIFO as environment.
* ``amba_jcss12`` — AMBA AHB arbiter, the original Bloem et al. (DATE'07 / JCSS'12) encoding
  with auxiliary monitors ``stateA1``, ``stateG2``, ``stateG3`` and ``stateG10_i``.
* ``amba_fm15`` — our reading of the Filippidis–Murray (Caltech TR 2015) revision: binary
  ``hmaster`` and binary ``grant`` (instead of one-hot grants), no ``busreq`` helper output,
  and the weakened A1 (only a *started* locked incremental burst obliges the master to
  eventually drop its request).  Harder than the published instances (docs/gr1.md).
* ``synt15`` — the SYNT'15 instances of that revision as published (open Promela,
  ``johnyf/gr1experiments`` ``examples/synt15/pml/synt15_<n>.txt``), re-encoded by us from
  the specification text with the monitor processes as program-counter automata; the
  anchor tools' synt15 numbers were measured on the same specification.

Unrealizable variants with a known verdict (the reason is in each docstring):
``arbiter_immediate``, ``amba_nohready``, ``genbuf_noreceiver``.

These are independent re-encodings (same informal specifications, our own bit-level
formulas), so timings are comparable with the anchor tools' instances in shape, not bit for
bit.  ``VERDICTS`` records the expected realizability of every family.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from specbuild import (  # noqa: E402
    AND,
    FALSE,
    OR,
    TRUE,
    F,
    SpecBuilder,
    bits_needed,
    iff,
    implies,
    vec_eq,
)


def arbiter(n: int) -> str:
    """PPS06 arbiter.  Env: a request stays until granted and is not raised again until the
    grant is withdrawn; GF ¬(r_i ∧ g_i).  Sys: grants mutually exclusive, a grant changes only
    while it differs from its request; GF (r_i ↔ g_i)."""
    s = SpecBuilder(f"PPS06 arbiter, n={n}")
    r = [s.input(f"r{i}") for i in range(n)]
    g = [s.output(f"g{i}") for i in range(n)]
    s.env_init(AND(~x for x in r))
    s.sys_init(AND(~x for x in g))
    for i in range(n):
        s.env_trans(implies(r[i] ^ g[i], iff(r[i].p, r[i])))
        s.env_live(~(r[i] & g[i]))
        s.sys_trans(implies(iff(r[i], g[i]), iff(g[i].p, g[i])))
        s.sys_live(iff(r[i], g[i]))
    for i in range(n):
        for k in range(i + 1, n):
            s.sys_trans(~(g[i].p & g[k].p))
    return s.text()


def arbiter_immediate(n: int) -> str:
    """UNREALIZABLE for n ≥ 2: every request must be granted in the same step
    (``r_i' → g_i'``) with mutually exclusive grants, and the environment may raise two
    requests at once."""
    s = SpecBuilder(f"arbiter with immediate grants (unrealizable), n={n}")
    r = [s.input(f"r{i}") for i in range(n)]
    g = [s.output(f"g{i}") for i in range(n)]
    s.env_init(AND(~x for x in r))
    s.sys_init(AND(~x for x in g))
    for i in range(n):
        s.sys_trans(implies(r[i].p, g[i].p))
        s.sys_live(iff(r[i], g[i]))
        for k in range(i + 1, n):
            s.sys_trans(~(g[i].p & g[k].p))
    return s.text()


def lift(n: int) -> str:
    """PPS06 lift.  Env: button i stays pressed until the lift is at floor i, then clears.
    Sys: one-hot floors, move at most one floor per step, ``up`` records an upward move, ``sb``
    mirrors "some button pressed", move up only if a button is pressed; GF (b_i → f_i) and
    GF (f_0 ∨ sb)."""
    s = SpecBuilder(f"PPS06 lift, n={n}")
    b = [s.input(f"b{i}") for i in range(n)]
    f = [s.output(f"f{i}") for i in range(n)]
    up = s.output("up")
    sb = s.output("sb")
    s.env_init(AND(~x for x in b))
    for i in range(n):
        s.env_trans(implies(b[i] & f[i], ~b[i].p))
        s.env_trans(implies(b[i] & ~f[i], b[i].p))
    s.sys_init(f[0] & AND(~x for x in f[1:]) & ~up & ~sb)
    for i in range(n):
        for k in range(i + 1, n):
            s.sys_trans(~(f[i].p & f[k].p))
    s.sys_trans(OR(x.p for x in f))
    for i in range(n):
        near = OR(f[k].p for k in (i - 1, i, i + 1) if 0 <= k < n)
        s.sys_trans(implies(f[i], near))
        if i + 1 < n:
            s.sys_trans(implies(f[i] & f[i + 1].p, sb))
    s.sys_trans(iff(up.p, OR(f[i] & f[i + 1].p for i in range(n - 1))))
    s.sys_trans(iff(sb.p, OR(x.p for x in b)))
    for i in range(n):
        s.sys_live(implies(b[i], f[i]))
    s.sys_live(f[0] | sb)
    return s.text()


def lift_gr1c(n: int) -> str:
    """The PPS06 lift as gr1c's example generator states it (``gen_liftspec.py``; re-encoded
    here from its formulas, one slugsin line per ``[]`` clause).  Env: button ``b_i`` clears
    once the lift is at floor ``i`` and stays pressed otherwise (no environment justice).  Sys:
    floors ``f_i`` pairwise exclusive (a constraint on the *current* state, one line), start at
    floor 0, move at most one floor per step, move up only while some button is pressed;
    GF (f_0 ∨ some button) and GF (b_i → f_i).  Unlike :func:`lift` there are no helper
    outputs (``up``, ``sb``) and no "some floor" constraint."""
    s = SpecBuilder(f"PPS06 lift (gr1c's formulation), n={n}")
    b = [s.input(f"b{i}") for i in range(n)]
    f = [s.output(f"f{i}") for i in range(n)]
    s.env_init(AND(~x for x in b))
    for i in range(n):
        s.env_trans(implies(b[i] & f[i], ~b[i].p) & implies(b[i] & ~f[i], b[i].p), split=False)
    s.sys_init(f[0] & AND(~x for x in f[1:]))
    any_b = OR(b)
    s.sys_trans(implies(OR(f[i] & f[i + 1].p for i in range(n - 1)), any_b), split=False)
    s.sys_trans(AND(~(f[i] & f[k]) for i in range(n) for k in range(i + 1, n)), split=False)
    for i in range(n):
        s.sys_trans(implies(f[i], OR(f[k].p for k in (i - 1, i, i + 1) if 0 <= k < n)))
    s.sys_live(f[0] | any_b)
    for i in range(n):
        s.sys_live(implies(b[i], f[i]))
    return s.text()


def _genbuf(n: int, receiver_fair: bool) -> str:
    s = SpecBuilder(f"GenBuf, {n} senders, 2 receivers" +
                    ("" if receiver_fair else " (no receiver fairness: unrealizable)"))
    sreq = [s.input(f"StoB_REQ{i}") for i in range(n)]
    rack = [s.input(f"RtoB_ACK{j}") for j in range(2)]
    full = s.input("FULL")
    empty = s.input("EMPTY")
    sack = [s.output(f"BtoS_ACK{i}") for i in range(n)]
    rreq = [s.output(f"BtoR_REQ{j}") for j in range(2)]
    enq = s.output("ENQ")
    deq = s.output("DEQ")
    w = bits_needed(n)
    slc = [s.output(f"SLC{k}") for k in range(w)]
    rr = s.output("rr")
    # environment: four-phase senders and receivers, FIFO flags
    s.env_init(AND(~x for x in sreq) & AND(~x for x in rack) & ~full & empty)
    for i in range(n):
        s.env_trans(implies(sreq[i] & ~sack[i], sreq[i].p))
        s.env_trans(implies(sack[i], ~sreq[i].p))
    for j in range(2):
        s.env_trans(implies(~rreq[j], ~rack[j].p))
        s.env_trans(implies(rreq[j] & rack[j], rack[j].p))
        if receiver_fair:
            s.env_live(iff(rreq[j], rack[j]))
    s.env_trans(implies(enq & ~deq, ~empty.p))
    s.env_trans(implies(deq & ~enq, ~full.p))
    s.env_trans(implies(iff(enq, deq), iff(full, full.p) & iff(empty, empty.p)))
    s.env_trans(~(full.p & empty.p))
    # system
    s.sys_init(AND(~x for x in sack + rreq + slc) & ~enq & ~deq & ~rr)
    rise = [~sack[i] & sack[i].p for i in range(n)]
    for i in range(n):
        s.sys_trans(implies(~sreq[i].p, ~sack[i].p))
        s.sys_trans(implies(sack[i] & sreq[i].p, sack[i].p))
        for k in range(i + 1, n):
            s.sys_trans(~(sack[i].p & sack[k].p))
        s.sys_trans(implies(rise[i], vec_eq([b.p for b in slc], i)))
        s.sys_live(iff(sreq[i], sack[i]))
    s.sys_trans(iff(enq.p, OR(rise)))
    s.sys_trans(implies(~enq.p, vec_eq([b.p for b in slc], 0)))
    s.sys_trans(implies(full.p, ~enq.p))
    for j in range(2):
        s.sys_trans(implies(rreq[j] & ~rack[j].p, rreq[j].p))
        s.sys_trans(implies(rack[j].p, ~rreq[j].p))
        s.sys_trans(implies(~rreq[j] & empty.p, ~rreq[j].p))
        # round robin: a new request goes to receiver rr; an ack passes the turn on
        mine = rr if j == 1 else ~rr
        s.sys_trans(implies(~rreq[j] & rreq[j].p, mine))
    s.sys_trans(~(rreq[0].p & rreq[1].p))
    served0 = rreq[0] & rack[0].p
    served1 = rreq[1] & rack[1].p
    s.sys_trans(iff(deq.p, served0 | served1))
    s.sys_trans(implies(served0, rr.p))
    s.sys_trans(implies(served1, ~rr.p))
    s.sys_trans(implies(~served0 & ~served1, iff(rr.p, rr)))
    s.sys_live(empty | rreq[0] | rreq[1])
    return s.text()


def genbuf(n: int) -> str:
    """GenBuf (Bloem et al.): n four-phase senders into a FIFO (modelled by the environment
    through FULL/EMPTY), two round-robin receivers; every request is eventually acknowledged
    (GF (StoB_REQ_i ↔ BtoS_ACK_i)) assuming receivers eventually answer."""
    return _genbuf(n, True)


def genbuf_noreceiver(n: int) -> str:
    """UNREALIZABLE: without receiver fairness the environment never acknowledges a
    receiver request, the buffer fills (FULL forbids ENQ) and senders starve."""
    return _genbuf(n, False)


def _amba_common(s: SpecBuilder, n: int):
    hb0, hb1 = s.input("hburst0"), s.input("hburst1")
    hbusreq = [s.input(f"hbusreq{i}") for i in range(n)]
    hlock = [s.input(f"hlock{i}") for i in range(n)]
    hready = s.input("hready")
    incr = hb0 & ~hb1
    burst4 = ~hb0 & hb1
    s.env_init(AND(~x for x in hbusreq + hlock) & ~hready & ~hb0 & ~hb1)
    for i in range(n):
        s.env_trans(implies(hlock[i].p, hbusreq[i].p))
    return hbusreq, hlock, hready, incr, burst4


def _g3(s: SpecBuilder, hmastlock: F, start: F, hready: F, burst4: F) -> None:
    """G3: a locked BURST4 transfer takes 4 hready cycles before the next start (counter)."""
    st = [s.output(f"stateG3_{k}") for k in range(3)]
    s.sys_init(AND(~x for x in st))
    c = [vec_eq(st, k) for k in range(5)]
    cp = [vec_eq([b.p for b in st], k) for k in range(5)]
    trig = hmastlock & start & burst4
    s.sys_trans(implies(c[0] & ~trig, cp[0]))
    s.sys_trans(implies(c[0] & trig & ~hready, cp[1]))
    s.sys_trans(implies(c[0] & trig & hready, cp[2]))
    for k in range(1, 5):
        s.sys_trans(implies(c[k] & start, FALSE))
        s.sys_trans(implies(c[k] & ~start & ~hready, cp[k]))
        s.sys_trans(implies(c[k] & ~start & hready, cp[(k + 1) % 5]))
    s.sys_trans(~OR(vec_eq([b.p for b in st], k) for k in (5, 6, 7)))  # unused codes


def _g2(s: SpecBuilder, hmastlock: F, start: F, incr: F, busreq: F) -> F:
    """G2: during a locked INCR burst no new start while the master keeps requesting."""
    g2 = s.output("stateG2")
    s.sys_init(~g2)
    trig = hmastlock & start & incr
    s.sys_trans(implies(~g2 & ~trig, ~g2.p))
    s.sys_trans(implies(~g2 & trig, g2.p))
    s.sys_trans(implies(g2 & start, FALSE))
    s.sys_trans(implies(g2 & ~start & busreq, g2.p))
    s.sys_trans(implies(g2 & ~start & ~busreq, ~g2.p))
    return g2


def _g10(s: SpecBuilder, n: int, grant_is: Callable[[int], F], hbusreq: list[F]) -> None:
    """G10: a master i ≥ 1 that was not granted is not granted before it requests."""
    for i in range(1, n):
        st = s.output(f"stateG10_{i}")
        s.sys_init(~st)
        gi = grant_is(i)
        s.sys_trans(implies(~st & (gi | hbusreq[i]), ~st.p))
        s.sys_trans(implies(~st & ~gi & ~hbusreq[i], st.p))
        s.sys_trans(implies(st & gi & ~hbusreq[i], FALSE))
        s.sys_trans(implies(st & hbusreq[i], ~st.p))
        s.sys_trans(implies(st & ~gi & ~hbusreq[i], st.p))


def _amba_jcss12(n: int, hready_fair: bool) -> str:
    s = SpecBuilder(f"AMBA AHB arbiter (Bloem et al. JCSS'12 encoding), n={n}" +
                    ("" if hready_fair else " without GF hready (unrealizable)"))
    hbusreq, hlock, hready, incr, burst4 = _amba_common(s, n)
    busreq = s.output("busreq")
    decide = s.output("decide")
    hgrant = [s.output(f"hgrant{i}") for i in range(n)]
    w = bits_needed(n)
    hmaster = [s.output(f"hmaster{k}") for k in range(w)]
    hmastlock = s.output("hmastlock")
    locked = s.output("locked")
    start = s.output("start")
    a1 = [s.output("stateA1_0"), s.output("stateA1_1")]
    m = [vec_eq(hmaster, i) for i in range(n)]
    mp = [vec_eq([b.p for b in hmaster], i) for i in range(n)]
    s.sys_init(m[0] & ~hmastlock & start & decide & ~locked & hgrant[0]
               & AND(~x for x in hgrant[1:]) & ~busreq & ~a1[0] & ~a1[1])
    for i in range(n):
        s.sys_trans(implies(m[i], iff(busreq, hbusreq[i])))
    if n < (1 << w):
        s.sys_trans(OR(mp))
    # A1 monitor (system-driven auxiliary; the environment promises GF ¬stateA1_1):
    # locked INCR burst → the master eventually drops its request
    a0, a1b = vec_eq(a1, 0), a1[1] & ~a1[0]
    a1c = ~a1[1] & a1[0]
    trig = hmastlock & incr
    to0 = vec_eq([b.p for b in a1], 0)
    to2 = a1[1].p & ~a1[0].p
    to1 = ~a1[1].p & a1[0].p
    s.sys_trans(implies(a0 & ~trig, to0))
    s.sys_trans(implies(a0 & trig, to2))
    s.sys_trans(implies(a1b & busreq, to2))
    s.sys_trans(implies(a1b & ~busreq & ~trig, to0))
    s.sys_trans(implies(a1b & ~busreq & trig, to1))
    s.sys_trans(implies(a1c & busreq, to2))
    s.sys_trans(implies(a1c & ~busreq & trig, to1))
    s.sys_trans(implies(a1c & ~busreq & ~trig, to0))
    s.sys_trans(~(a1[0].p & a1[1].p))
    s.env_live(~a1[1])
    if hready_fair:
        s.env_live(hready)
    # G1
    s.sys_trans(implies(~hready, ~start.p))
    g2 = _g2(s, hmastlock, start, incr, busreq)
    _g3(s, hmastlock, start, hready, burst4)
    for i in range(n):
        s.sys_trans(implies(hready, iff(hgrant[i], mp[i])))  # G4
    s.sys_trans(implies(hready, iff(locked, hmastlock.p)))  # G5
    for i in range(n):  # G6
        s.sys_trans(implies(~start.p, iff(m[i], mp[i])))
    s.sys_trans(implies(~start.p, iff(hmastlock, hmastlock.p)))
    for i in range(n):  # G7
        s.sys_trans(implies(decide & hlock[i] & hgrant[i].p, locked.p))
        s.sys_trans(implies(decide & ~hlock[i] & hgrant[i].p, ~locked.p))
    for i in range(n):  # G8
        s.sys_trans(implies(~decide, iff(hgrant[i], hgrant[i].p)))
    s.sys_trans(implies(~decide, iff(locked, locked.p)))
    _g10(s, n, lambda i: hgrant[i], hbusreq)
    s.sys_trans(implies(decide & AND(~x for x in hbusreq), hgrant[0].p))
    for i in range(n):  # exactly one grant
        for k in range(i + 1, n):
            s.sys_trans(~(hgrant[i].p & hgrant[k].p))
    s.sys_trans(OR(x.p for x in hgrant))
    s.sys_live(~g2)
    for i in range(n):
        s.sys_live(m[i] | ~hbusreq[i])
    return s.text()


def amba_jcss12(n: int) -> str:
    """AMBA AHB arbiter, original encoding (see the module docstring)."""
    return _amba_jcss12(n, True)


def amba_nohready(n: int) -> str:
    """UNREALIZABLE for n ≥ 2: without GF hready the slave may stall forever; then no new
    transfer starts (G1), the master cannot change (G6) and a requesting master ≠ 0 is
    never served."""
    return _amba_jcss12(n, False)


def amba_fm15(n: int) -> str:
    """AMBA AHB arbiter in the style of the Filippidis–Murray revision (module docstring)."""
    s = SpecBuilder(f"AMBA AHB arbiter (Filippidis-Murray style revision), n={n}")
    hbusreq, hlock, hready, incr, burst4 = _amba_common(s, n)
    w = bits_needed(n)
    hmaster = [s.output(f"hmaster{k}") for k in range(w)]
    grant = [s.output(f"grant{k}") for k in range(w)]
    decide = s.output("decide")
    hmastlock = s.output("hmastlock")
    locked = s.output("locked")
    start = s.output("start")
    a1 = s.output("stateA1")
    m = [vec_eq(hmaster, i) for i in range(n)]
    mp = [vec_eq([b.p for b in hmaster], i) for i in range(n)]
    gr = [vec_eq(grant, i) for i in range(n)]
    grp = [vec_eq([b.p for b in grant], i) for i in range(n)]
    busreq = OR(m[i] & hbusreq[i] for i in range(n))
    busreq_p = OR(mp[i] & hbusreq[i].p for i in range(n))
    s.sys_init(m[0] & gr[0] & ~hmastlock & start & decide & ~locked & ~a1)
    if n < (1 << w):
        s.sys_trans(OR(mp))
        s.sys_trans(OR(grp))
    # weakened A1: only a started locked INCR burst creates the obligation
    s.sys_trans(iff(a1.p, (a1 | (hmastlock & incr & start)) & busreq_p))
    s.env_live(~a1)
    s.env_live(hready)
    s.sys_trans(implies(~hready, ~start.p))  # G1
    g2 = _g2(s, hmastlock, start, incr, busreq)
    _g3(s, hmastlock, start, hready, burst4)
    for i in range(n):
        s.sys_trans(implies(hready, iff(gr[i], mp[i])))  # G4
    s.sys_trans(implies(hready, iff(locked, hmastlock.p)))  # G5
    for i in range(n):
        s.sys_trans(implies(~start.p, iff(m[i], mp[i])))  # G6
    s.sys_trans(implies(~start.p, iff(hmastlock, hmastlock.p)))
    for i in range(n):  # G7
        s.sys_trans(implies(decide & grp[i], iff(locked.p, hlock[i])))
    for k in range(w):  # G8
        s.sys_trans(implies(~decide, iff(grant[k], grant[k].p)))
    s.sys_trans(implies(~decide, iff(locked, locked.p)))
    _g10(s, n, lambda i: gr[i], hbusreq)
    s.sys_trans(implies(decide & AND(~x for x in hbusreq), grp[0]))
    s.sys_live(~g2)
    for i in range(n):
        s.sys_live(m[i] | ~hbusreq[i])
    return s.text()


def _le(bits: list[F], bound: int) -> F:
    """``bits <= bound`` (LSB first, unsigned); TRUE when every pattern is in range."""
    if bound >= (1 << len(bits)) - 1:
        return TRUE
    out = TRUE  # bits[:k] <= bound's low k bits; the higher bit decides, ties go down
    for k, b in enumerate(bits):
        out = (~b | out) if (bound >> k) & 1 else (~b & out)
    return out


def _edges(pc: F, pc_next: F, nodes: dict[int, list[tuple[int, F]]]) -> list[F]:
    """One TRANS line per program-graph node ``u`` of a one-bit program counter:
    ``pc = u → ⋁ (pc' = v ∧ formula)`` over the node's out-edges ``(v, formula)``."""
    lines = []
    for u, out in nodes.items():
        at_u = pc if u else ~pc
        lines.append(implies(at_u, OR((pc_next if v else ~pc_next) & f for v, f in out)))
    return lines


@dataclass(frozen=True)
class Synt15Vars:
    """The declared variables of a synt15 instance (integers as LSB-first bit lists)."""

    n: int
    ready: F
    burst: list[F]
    request: list[F]
    grantee_lockreq: F
    master_lockreq: F
    start: F
    decide: F
    lock: F
    lockmemo: F
    master: list[F]
    grant: list[F]
    decide_prev: F


def synt15(n: int) -> str:
    """The Filippidis–Murray AMBA AHB arbiter exactly as published for SYNT'15
    (``johnyf/gr1experiments``, ``examples/synt15/pml/synt15_<n>.txt``, open Promela), with
    ``n`` masters, re-encoded here from the specification text; the choices made for open
    Promela's semantics are in docs/gr1.md ("synt15").

    Environment: ``ready``, ``burst`` ∈ 0..2 (SINGLE, BURST4, INCR), ``request[0..n-1]``,
    ``grantee_lockreq``, ``master_lockreq`` and the program counter of the assumption
    process ``withdraw_lock`` (A1).  System: ``start``, ``decide``, ``lock``, ``lockmemo``,
    ``master``, ``grant`` ∈ 0..n-1 (binary), ``decide_prev`` (the value of ``--X decide``),
    and the program counters of ``maintain_lock`` (G2) and ``count_burst`` (G3) with G3's
    local ``count`` ∈ 0..3.
    """
    return synt15_spec(n, synt15_processes).text()


def synt15_spec(n: int, processes: Callable[[SpecBuilder, Synt15Vars], None]) -> SpecBuilder:
    """synt15 with the proctypes encoded by ``processes`` (which declares its own program
    counters); the tests compare :func:`synt15_processes` with a literal transcription of
    open Promela's translation."""
    s = SpecBuilder(f"AMBA AHB arbiter, SYNT'15 instance (Filippidis-Murray), {n} masters")
    w = bits_needed(n)
    v = Synt15Vars(
        n=n, ready=s.input("ready"), burst=[s.input(f"burst{k}") for k in range(2)],
        request=[s.input(f"request{i}") for i in range(n)],
        grantee_lockreq=s.input("grantee_lockreq"), master_lockreq=s.input("master_lockreq"),
        start=s.output("start"), decide=s.output("decide"), lock=s.output("lock"),
        lockmemo=s.output("lockmemo"), master=[s.output(f"master{k}") for k in range(w)],
        grant=[s.output(f"grant{k}") for k in range(w)], decide_prev=s.output("decide_prev"))
    _synt15_variables(s, v)
    _synt15_ltl(s, v)
    processes(s, v)
    for i in range(n):
        s.sys_live(implies(v.request[i], vec_eq(v.master, i)))
    return s


def _synt15_variables(s: SpecBuilder, v: Synt15Vars) -> None:
    """Initial values of the declarations (A4, G11; ``free`` without a value = any value
    in range) and the range constraints of the integers (init and primed, as slugs does)."""
    s.env_init(~v.ready & AND(~r for r in v.request) & ~v.grantee_lockreq & ~v.master_lockreq
               & _le(v.burst, 2))
    s.env_trans(_le([b.p for b in v.burst], 2))
    s.sys_init(v.start & v.decide & ~v.lock & vec_eq(v.master, 0) & _le(v.grant, v.n - 1))
    s.sys_trans(_le([b.p for b in v.master], v.n - 1) & _le([b.p for b in v.grant], v.n - 1))


def _synt15_ltl(s: SpecBuilder, v: Synt15Vars) -> None:
    """A2 and the ``assert ltl { [](...) }`` block: G1, G4–G8, G10; ``--X decide`` is the
    one-bit memory ``decide_prev`` (false at time 0: strong previous)."""
    s.env_live(v.ready)  # A2
    s.sys_trans(implies(v.start.p, v.ready))  # G1
    s.sys_trans(implies(v.ready, AND(iff(m.p, g) for m, g in zip(v.master, v.grant, strict=True))
                        & iff(v.lock.p, v.lockmemo.p)), split=False)  # G4, G5
    s.sys_trans(implies(~v.start.p, AND(iff(m.p, m) for m in v.master)
                        & iff(v.lock.p, v.lock)), split=False)  # G6
    s.sys_trans(implies(v.decide_prev, iff(v.lockmemo.p, v.grantee_lockreq.p)))  # G7
    s.sys_trans(implies(~v.decide, AND(iff(g.p, g) for g in v.grant)), split=False)  # G8
    s.sys_trans(implies(~v.decide_prev, iff(v.lockmemo.p, v.lockmemo)))  # G8
    grant_p = [g.p for g in v.grant]
    s.sys_trans(AND(iff(g.p, g) for g in v.grant) | vec_eq(grant_p, 0)
                | OR(vec_eq(grant_p, i) & v.request[i] for i in range(1, v.n)),
                split=False)  # G10
    s.sys_init(~v.decide_prev)
    s.sys_trans(iff(v.decide_prev.p, v.decide))


def synt15_processes(s: SpecBuilder, v: Synt15Vars) -> None:
    """The three proctypes of the ``sync{}`` block and A1, each a two-node program graph
    that takes exactly one enabled edge per step; node 0 is the outer ``do``."""
    pc_a1 = s.input("pc_withdraw_lock")
    pc_g2 = s.output("pc_maintain_lock")
    pc_g3 = s.output("pc_count_burst")
    count = [s.output(f"count{k}") for k in range(2)]
    # A1 (env): do :: lock; do :: !master_lockreq'; break :: true od :: else od, with
    # the progress label on node 0
    s.env_init(~pc_a1)
    for line in _edges(pc_a1, pc_a1.p, {0: [(1, v.lock), (0, ~v.lock)],
                                         1: [(0, ~v.master_lockreq.p), (1, TRUE)]}):
        s.env_trans(line, split=False)
    s.env_live(~pc_a1)
    # G2 (sys): do :: (lock && start && burst == INCR); do :: (!start && !master_lockreq');
    # break :: !start od :: else od
    trig2 = v.lock & v.start & vec_eq(v.burst, 2)
    s.sys_init(~pc_g2)
    g2 = {0: [(1, trig2), (0, ~trig2)],
          1: [(0, ~v.start & ~v.master_lockreq.p), (1, ~v.start)]}
    for line in _edges(pc_g2, pc_g2.p, g2):
        s.sys_trans(line, split=False)
    # G3 (sys): count is imperative (unchanged except on the two edges that prime it)
    s.sys_init(~pc_g3 & vec_eq(count, 0))
    for line in _edges(pc_g3, pc_g3.p, _count_burst_edges(v, count)):
        s.sys_trans(line, split=False)


def _count_burst_edges(v: Synt15Vars, count: list[F]) -> dict[int, list[tuple[int, F]]]:
    """G3's program graph with the frame of ``count`` folded into the edges."""
    cp = [c.p for c in count]
    keep = AND(iff(c.p, c) for c in count)
    trig3 = v.start & v.lock & vec_eq(v.burst, 1)
    first = trig3 & implies(v.ready, vec_eq(cp, 1)) & implies(~v.ready, vec_eq(cp, 0))
    step = OR(vec_eq(count, k) & vec_eq(cp, k + 1) for k in range(3))
    return {0: [(1, first), (0, ~trig3 & keep)],
            1: [(1, ~v.start & ~v.ready & keep), (1, ~v.start & v.ready & step),
                (0, ~v.start & v.ready & vec_eq(count, 3) & keep)]}


FAMILIES: dict[str, Callable[[int], str]] = {
    "arbiter": arbiter,
    "lift": lift,
    "lift_gr1c": lift_gr1c,
    "genbuf": genbuf,
    "amba_jcss12": amba_jcss12,
    "amba_fm15": amba_fm15,
    "synt15": synt15,
    "arbiter_immediate": arbiter_immediate,
    "amba_nohready": amba_nohready,
    "genbuf_noreceiver": genbuf_noreceiver,
}

# expected realizability (for n ≥ 2)
VERDICTS: dict[str, bool] = {
    "arbiter": True,
    "lift": True,
    "lift_gr1c": True,
    "genbuf": True,
    "amba_jcss12": True,
    "amba_fm15": True,
    "synt15": True,
    "arbiter_immediate": False,
    "amba_nohready": False,
    "genbuf_noreceiver": False,
}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("family", nargs="?", choices=sorted(FAMILIES))
    ap.add_argument("n", nargs="?", type=int)
    ap.add_argument("-o", "--output", help="write to FILE instead of stdout")
    ap.add_argument("--list", action="store_true", help="list families and verdicts")
    args = ap.parse_args(argv)
    if args.list or args.family is None:
        for name in FAMILIES:
            print(f"{name:20s} {'realizable' if VERDICTS[name] else 'unrealizable'}")
        return 0
    if args.n is None or args.n < 2:
        ap.error("n must be at least 2")
    text = FAMILIES[args.family](args.n)
    if args.output:
        Path(args.output).write_text(text, encoding="utf-8")
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
