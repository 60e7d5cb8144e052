"""Framing by variable (symbolic_game.SymbolicGame.framed_to): with shared fluent variables a
machine outside a relation group may read a variable an owner writes, so the frame of a
merged (framed) relation must keep exactly the variables *no owner* moves.  Framing per
machine dropped an owner's move into ERROR (which clears its feature bits) whenever another
machine tracking the same fluent did not take part: the environment lost a move and the
symbolic game called a losing spec realizable (found on SYNTECH15 GyroLTL_637)."""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from synthesis_helpers import F, fl, problem
from test_agreement import problems

from iterplan_compiler.ir.lts import ERROR, make_lts
from iterplan_compiler.symbolic.bdd import and_exists
from iterplan_compiler.synthesis.driver import synthesize
from iterplan_compiler.synthesis.encode import prepare
from iterplan_compiler.synthesis.explicit import ProductMoves
from iterplan_compiler.synthesis.recode import recode_leaves
from iterplan_compiler.synthesis.symbolic_game import SymbolicGame

# P cycles on -> off -> ack; S tracks the same fluents (same keys, so shared variables) and
# may also crash (uncontrollable, S alone) where the shared `ack` feature is 1.
CYCLE = [(0, "on", 1), (1, "off", 2), (2, "ack", 0)]
P = make_lts("P", 3, CYCLE)
S = make_lts("S", 3, CYCLE + [(0, "crash", ERROR)])
ON = fl("On", {"on"}, {"off"})
SPEC = problem(P, controllable={"on", "off"}, safety=(S,), fluents=[ON], guarantees=(F("On"),))


def _successors(game: SymbolicGame, tup: tuple[int, ...], controllable: bool
                ) -> set[tuple[int, ...] | None]:
    """The symbolic game's successors of one state (None: a successor with a component at
    ERROR)."""
    b = game.bdd
    cube = game.state_cube(tup)
    out: set[tuple[int, ...] | None] = set()
    for g in game.groups:
        if g.controllable != controllable:
            continue
        img = b.let(g.unprime, and_exists(b, g.rel, cube, g.cur_vars)) & game.valid
        for a in b.pick_iter(img, care_vars=game.cur_vars):
            out.add(None if b.let(a, game.error) == b.true else game.decode(a, game.cur))
    return out


def _moves_agree(spec) -> None:
    """Every reachable state of the explicit product has exactly the symbolic moves."""
    game = SymbolicGame(spec)
    pm = ProductMoves(spec.components)
    seen, todo = {pm.start}, [pm.start]
    while todo:
        s = todo.pop()
        moves = pm.moves(s)
        for ctrl in (True, False):
            want = {t for a, t in moves if (a in spec.controllable) == ctrl}
            assert _successors(game, s, ctrl) == want, (s, ctrl)
        for _, t in moves:
            if t is not None and t not in seen:
                seen.add(t)
                todo.append(t)


def test_shared_fluent_keys_and_one_framed_group():
    """The set-up really exercises the bug: P and S share feature variables, and the
    uncontrollable groups {ack: P, S} and {crash: S} are merged into one framed relation."""
    spec = recode_leaves(prepare(SPEC))
    keys = spec.bit_keys
    assert set(keys[0]) & set(keys[1]) - {None}
    game = SymbolicGame(spec)
    unc = [g for g in game.groups if not g.controllable]
    assert len(unc) == 1 and set(unc[0].actions) == {"ack", "crash"}
    assert len(unc[0].owners) == len(game.cur)


def test_error_move_of_one_sharer_is_kept():
    _moves_agree(recode_leaves(prepare(SPEC)))
    game = SymbolicGame(recode_leaves(prepare(SPEC)))
    assert game.init & game.env != game.bdd.false  # crash is enabled initially


def test_verdict_matches_the_explicit_oracle():
    """The environment crashes at once: unrealizable (the per-machine frame said realizable)."""
    verdicts = {s: synthesize(SPEC, solver=s).realizable for s in ("symbolic", "explicit")}
    assert verdicts == {"symbolic": False, "explicit": False}


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_recoded_moves_are_product_moves(prob):
    """Random problems: the recoded, shared-variable game has the product's moves."""
    _moves_agree(recode_leaves(prepare(prob)))
