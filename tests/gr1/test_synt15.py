"""synt15: our process encoding against a literal transcription of open Promela's translation.

``generators.synt15_processes`` writes each proctype as ``pc = u → ⋁ (pc' = v ∧ statement)``
and drops what open Promela adds around it (docs/gr1.md, "synt15").  Here the same proctypes
are written the way open Promela's translator states them: per-process edge keys, one
scheduler variable per player (``ps0`` for the environment's group, ``ps1`` for the system's
``sync`` group) with the deadlock value, executability guards in which a primed variable of
the process' own player counts as true, the dataflow constraint only when the group is
scheduled, idle program counters, and the imperative ``count`` kept unless one of its two
assigning edges is taken.  Both encodings must give the same winning set on the shared
variables, and the literal one must not depend on its keys or scheduler values.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from iterplan_compiler.gr1.slugsin import parse
from iterplan_compiler.gr1.solve import solve

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks" / "gr1"))

import generators  # noqa: E402
from specbuild import AND, OR, TRUE, F, SpecBuilder, iff, implies, vec_eq  # noqa: E402

# (u, v, key, statement, executability guard)
Edge = tuple[int, int, int, F, F]


def _at(pc: F, u: int) -> F:
    return pc if u else ~pc


def _process(pc: F, key: list[F], edges: list[Edge]) -> tuple[F, F]:
    """(dataflow constraint, "blocked" condition) of a two-node program graph."""
    flow = []
    blocked = []
    for u in (0, 1):
        out = [e for e in edges if e[0] == u]
        flow.append(implies(_at(pc, u), OR(_at(pc.p, v) & vec_eq([b.p for b in key], k) & stmt
                                           for _, v, k, stmt, _ in out)))
        blocked.append(_at(pc, u) & ~OR(guard for *_, guard in out))
    return AND(flow), OR(blocked)


def _keys(s: SpecBuilder, name: str, env: bool) -> list[F]:
    """A key with domain 0..2 (the largest edge multiplicity is 2), range-constrained."""
    bits = [(s.input if env else s.output)(f"{name}{b}") for b in range(2)]
    in_range = ~(bits[0] & bits[1])
    (s.env_init if env else s.sys_init)(in_range)
    (s.env_trans if env else s.sys_trans)(in_range.p)
    return bits


def literal_processes(s: SpecBuilder, v: generators.Synt15Vars) -> None:
    ps0, ps1 = s.input("ps0"), s.input("ps1")
    pc_a1 = s.input("pc_withdraw_lock")
    key_a1 = _keys(s, "envenvkey0_", env=True)
    pc_g2, pc_g3 = s.output("pc_maintain_lock"), s.output("pc_count_burst")
    count = [s.output(f"count{k}") for k in range(2)]
    key_g2, key_g3 = _keys(s, "syssyskey0_", env=False), _keys(s, "syssyskey1_", env=False)
    mlr_p, cp = v.master_lockreq.p, [c.p for c in count]
    trig2 = v.lock & v.start & vec_eq(v.burst, 2)
    trig3 = v.start & v.lock & vec_eq(v.burst, 1)
    first = trig3 & (~v.ready | vec_eq(cp, 1)) & (v.ready | vec_eq(cp, 0))
    less3 = ~(count[0] & count[1])
    step = OR(vec_eq(count, k) & vec_eq(cp, k + 1) for k in range(3))
    a1: list[Edge] = [(0, 1, 0, v.lock, v.lock), (0, 0, 0, ~v.lock, ~v.lock),
                      (1, 0, 0, ~mlr_p, TRUE), (1, 1, 0, TRUE, TRUE)]
    g2: list[Edge] = [(0, 1, 0, trig2, trig2), (0, 0, 0, ~trig2, ~trig2),
                      (1, 0, 0, ~v.start & ~mlr_p, ~v.start & ~mlr_p),
                      (1, 1, 0, ~v.start, ~v.start)]
    g3: list[Edge] = [(0, 1, 0, first, trig3), (0, 0, 0, ~trig3, ~trig3),
                      (1, 1, 0, ~v.start & ~v.ready, ~v.start & ~v.ready),
                      (1, 1, 1, ~v.start & v.ready & less3 & step, ~v.start & v.ready & less3),
                      (1, 0, 0, ~v.start & v.ready & ~less3, ~v.start & v.ready & ~less3)]
    flow_a1, blocked_a1 = _process(pc_a1, key_a1, a1)
    flow_g2, blocked_g2 = _process(pc_g2, key_g2, g2)
    flow_g3, blocked_g3 = _process(pc_g3, key_g3, g3)
    s.env_init(~pc_a1)
    s.sys_init(~pc_g2 & ~pc_g3 & vec_eq(count, 0))
    # environment group (ps0 = 0: withdraw_lock runs, 1: deadlock)
    s.env_trans(implies(~ps0.p, flow_a1), split=False)
    s.env_trans(implies(ps0.p, iff(pc_a1.p, pc_a1)))
    s.env_trans(implies(blocked_a1, ps0.p), split=False)  # blocked: not scheduled, deadlock
    s.env_trans(~ps0.p)  # the environment never deadlocks
    s.env_live(~ps0 & ~pc_a1)  # progress label
    # system group (ps1 = 0: the sync product runs, 1: deadlock)
    s.env_trans(iff(blocked_g2 | blocked_g3, ps1.p), split=False)
    s.sys_trans(~ps1.p)  # the system never deadlocks
    for flow, pc in ((flow_g2, pc_g2), (flow_g3, pc_g3)):
        s.sys_trans(implies(~ps1.p, flow), split=False)
        s.sys_trans(implies(ps1.p, iff(pc.p, pc)))
    assigns = ~ps1.p & ((~pc_g3 & pc_g3.p & vec_eq([b.p for b in key_g3], 0))
                        | (pc_g3 & pc_g3.p & vec_eq([b.p for b in key_g3], 1)))
    s.sys_trans(assigns | AND(iff(c.p, c) for c in count), split=False)


@pytest.mark.parametrize("n", [2, 3])
def test_literal_translation_has_the_same_winning_set(n):
    ours, _ = parse(generators.synt15(n))
    lit, diags = parse(generators.synt15_spec(n, literal_processes).text())
    assert lit is not None, diags
    res_o, _ = solve(ours, strategy=False)
    res_l, _ = solve(lit, strategy=False)
    assert res_o.realizable and res_l.realizable
    bdd_l, bdd_o = res_l.game.bdd, res_o.game.bdd
    extra = set(lit.inputs + lit.outputs) - set(ours.inputs + ours.outputs)
    assert extra == {"ps0", "ps1", "envenvkey0_0", "envenvkey0_1", "syssyskey0_0",
                     "syssyskey0_1", "syssyskey1_0", "syssyskey1_1"}
    some = bdd_l.exist(extra, res_l.winning)
    assert some == bdd_l.forall(extra, res_l.winning)  # keys and schedulers do not matter
    assert bdd_l.copy(some, bdd_o) == res_o.winning
