"""Explanations for unrealizable specifications, as a *play*: the environment's winning moves.

The environment wins from the initial state; the explanation is one play in which it does,
written with the spec's action names and the fluent values they change (never game state
numbers):

* **safety** — if the environment can force a dead end (a move into ERROR, i.e. a violated
  safety property; a deadlock; a controller state without a controllable move), the shortest
  forcing play, each controller step with all its alternatives (they all lose), ending with the
  step that breaks the property, named;
* **liveness** — otherwise the environment's layered strategy (the dual of the GR(1)
  fixpoint): layer 0 forces ERROR; each further layer is forced into the layers below or into
  a *core* where the environment keeps one guarantee ``G_j`` false while making every
  assumption ``A_i`` hold again and again (a generalised Büchi game for the environment).
  Played against a curious controller, the play is a lasso: a prefix (in which the environment
  may switch the guarantee it blocks as the controller's choices require), then a loop in one
  core, closed when a (state, guarantee, next assumption) triple repeats, with the loop steps
  after which each assumption holds; with no assumptions the text says so.  If the
  controller's choices lead into layer 0 the play ends with the step that breaks a property;
* a last resort (the layers always reach the initial state of a losing game; kept for
  safety): the head and the distinct fluent valuations of a few losing states.

Counts are of reachable non-ERROR game states, as both solvers report them (:func:`losing_head`).
"""

from __future__ import annotations

from dataclasses import dataclass

from iterplan_compiler.ir.formulas import show as show_formula
from iterplan_compiler.ir.lts import ERROR
from iterplan_compiler.synthesis.encode import GameSpec
from iterplan_compiler.synthesis.explicit import ExplicitGame

MAX_STEPS = 40


def losing_head(losing: int | None, total: int | None) -> str:
    """The first line of every explanation (``None``: the count is not known exactly)."""
    if losing is None or total is None:
        return "unrealizable: the initial state is losing"
    return (f"unrealizable: the initial state is losing ({losing} of {total} reachable "
            "game states are losing, ERROR not counted)")


def losing_count(game: ExplicitGame, win: frozenset[int]) -> tuple[int, int]:
    """``(losing, total)`` over the reachable non-ERROR states of ``game``."""
    states = [s for s in range(game.num_states) if s != game.error]
    return sum(1 for s in states if s not in win), len(states)


# --------------------------------------------------------------------------------------------
# A play and how it is printed


@dataclass(frozen=True, slots=True)
class Step:
    """One move of the play from game state ``state`` to ``target`` by ``action``.

    ``alternatives`` — for a controller move, every controllable action it had (all lose);
    ``note`` — what the step does to the goal (a violated property, an assumption visit)."""

    state: int
    action: str
    target: int
    by_controller: bool
    alternatives: tuple[str, ...] = ()
    note: str = ""


class Printer:
    """Renders steps with the fluent values each one changes."""

    def __init__(self, spec: GameSpec, game: ExplicitGame) -> None:
        self.spec, self.game = spec, game
        self.nbody = spec.num_plant + spec.num_safety

    def fluents(self, s: int) -> dict[str, bool]:
        tup = self.game.tuples[s] if s < len(self.game.tuples) else None
        if tup is None:
            return {}
        return {f: tup[self.nbody + k] == 1 for k, f in enumerate(self.spec.fluent_names)}

    def initially(self) -> str:
        vals = self.fluents(self.game.initial)
        if not vals:
            return "  initially: (no fluents)"
        return "  initially: " + ", ".join(f"{f}={_tf(v)}" for f, v in vals.items())

    def step(self, n: int, st: Step) -> str:
        who = "controller " if st.by_controller else "environment"
        what = st.action
        if st.by_controller:
            others = [a for a in st.alternatives if a != st.action]
            what += f" (all its choices lose: {', '.join(st.alternatives)})" if others else \
                " (its only move)"
        before, after = self.fluents(st.state), self.fluents(st.target)
        changed = [f"{f}={_tf(v)}" for f, v in after.items() if before.get(f) != v]
        tail = "  ".join(x for x in (st.note, ", ".join(changed)) if x)
        return f"  {n:>3}. {who}  {what}" + (f"    {tail}" if tail else "")


def _tf(v: bool) -> str:
    return "true" if v else "false"


# --------------------------------------------------------------------------------------------
# The environment's attractor and its moves


def _env_pre_layers(game: ExplicitGame, target: set[int], within: set[int],
                    avoid: frozenset[int] = frozenset()) -> dict[int, int]:
    """Environment attractor of ``target`` inside ``within``: state -> layer index.

    Controller moves into ``avoid`` (dead ends, which lose for the controller) are ignored:
    the controller does not take them while it has another move."""
    ctrl = game.controllable
    layer = {s: 0 for s in target}
    k = 0
    changed = True
    while changed:
        changed = False
        k += 1
        new = []
        for s in within:
            if s in layer:
                continue
            if game.env[s]:
                if any(a not in ctrl and t in layer for a, t in game.edges[s]):
                    new.append(s)
            else:
                cs = [t for a, t in game.edges[s] if a in ctrl and t not in avoid]
                if all(t in layer for t in cs):  # includes "no controllable move" (dead end)
                    new.append(s)
        for s in new:
            layer[s] = k
            changed = True
    return layer


def _move(game: ExplicitGame, layer: dict[int, int], s: int, allowed: set[int] | None = None,
          avoid: frozenset[int] = frozenset()) -> Step | None:
    """The environment's move down ``layer`` (or the controller's best-ranked choice; every
    choice is inside ``allowed``/``layer`` by construction); ``None`` without a move."""
    ctrl = game.controllable
    ok = allowed if allowed is not None else layer
    far = 1 << 30
    if game.env[s]:
        cands = [(layer.get(t, far), a, t) for a, t in game.edges[s] if a not in ctrl and t in ok]
        if not cands:
            return None
        _, a, t = min(cands)
        return Step(s, a, t, False)
    moves = sorted((a, t) for a, t in game.edges[s] if a in ctrl)
    if not moves:
        return None
    sensible = [m for m in moves if m[1] not in avoid] or moves
    a, t = min(sensible, key=lambda m: (layer.get(m[1], far), m[0]))
    return Step(s, a, t, True, tuple(sorted({x for x, _ in moves})))


def _env_can_stay(game: ExplicitGame, s: int, Z: set[int],
                  avoid: frozenset[int] = frozenset()) -> bool:
    ctrl = game.controllable
    if game.env[s]:
        return any(a not in ctrl and t in Z for a, t in game.edges[s])
    cs = [t for a, t in game.edges[s] if a in ctrl and t not in avoid]
    return bool(cs) and all(t in Z for t in cs)


def _env_buchi(game: ExplicitGame, region: set[int], assumptions: list[frozenset[int]],
               avoid: frozenset[int] = frozenset(), below: frozenset[int] = frozenset()
               ) -> set[int]:
    """Largest ``Z ⊆ region`` where the environment can stay forever (or move into
    ``below``, where it already wins) and force a visit to every assumption set again and
    again (generalised Büchi for the environment)."""
    Z = set(region)
    while True:
        new = set(Z)
        ok = Z | below
        for a in assumptions:
            target = {s for s in Z if s in a and _env_can_stay(game, s, ok, avoid)} | below
            new &= set(_env_pre_layers(game, target, ok, avoid))
        if new == Z:
            return Z
        Z = new


def _forcing_prefix(game: ExplicitGame, layer: dict[int, int], start: int, stop: set[int],
                    avoid: frozenset[int] = frozenset()) -> tuple[list[Step], int]:
    """Moves down ``layer`` from ``start`` until a state of ``stop``; the last state."""
    steps: list[Step] = []
    s = start
    while s not in stop and len(steps) < MAX_STEPS:
        st = _move(game, layer, s, avoid=avoid)
        if st is None:
            break
        steps.append(st)
        s = st.target
    return steps, s


# --------------------------------------------------------------------------------------------
# The two kinds of play


def _violation(spec: GameSpec, game: ExplicitGame, st: Step) -> str:
    """What the move ``st`` into ERROR violates: the machines that move to ERROR on it."""
    tup = game.tuples[st.state]
    if tup is None:
        return "reaches ERROR"
    names = []
    for k, c in enumerate(spec.components[:spec.num_plant + spec.num_safety]):
        if (st.action, ERROR) in c.out_edges().get(tup[k], []):
            kind = "safety property" if k >= spec.num_plant else "property"
            names.append(f"{kind} {c.name}")
    return "violates " + ", ".join(names) if names else "reaches ERROR"


def _safety_play(spec: GameSpec, game: ExplicitGame, dead: set[int]) -> list[str] | None:
    """The forcing play into a dead end, or ``None`` if the environment cannot force one."""
    attr = _env_pre_layers(game, dead, set(range(game.num_states)))
    if game.initial not in attr:
        return None
    steps, end = _forcing_prefix(game, attr, game.initial, dead)
    if end == game.error and steps:
        steps[-1] = _with_note(steps[-1], _violation(spec, game, steps[-1]))
        broken = steps[-1].note.removeprefix("violates ")
        head = f"the environment forces a violation of {broken} (a safety violation):"
        last = "the step marked 'violates' breaks it; every controller choice on the way loses."
    elif not game.edges[end]:
        head = "the environment forces a deadlock (no action is possible):"
        last = "the play stops there: a deadlock."
    else:
        head = "the environment forces a state where the controller has no move:"
        last = "the controller cannot move there, and the environment need not."
    p = Printer(spec, game)
    return [head, p.initially(), *(p.step(n, st) for n, st in enumerate(steps, 1)),
            "  " + last]


def _with_note(st: Step, note: str) -> Step:
    joined = f"{st.note}; {note}" if st.note else note
    return Step(st.state, st.action, st.target, st.by_controller, st.alternatives, joined)


@dataclass(frozen=True, slots=True)
class _Layer:
    """One round of the environment's winning region, built from the ones below it: in a
    ``cores[j]`` state the environment keeps guarantee ``j`` false (or drops to ``below``)
    while visiting every assumption; ``attr`` forces into ``below`` or a core."""

    below: frozenset[int]
    cores: dict[int, frozenset[int]]
    attr: dict[int, int]


def _layers(game: ExplicitGame, losing: set[int], avoid: frozenset[int]
            ) -> tuple[dict[int, int], list[_Layer]]:
    """``state -> layer`` and the layers of the environment's winning region (the dual of
    the GR(1) fixpoint: ``μZ. ∨_j νY. ∧_i μX. ...`` for the environment)."""
    dead = set(avoid)
    safety = _env_pre_layers(game, dead, losing | dead)  # layer 0: the environment forces ERROR
    rank = {s: 0 for s in safety}
    layers = [_Layer(frozenset(), {}, safety)]
    below = set(safety)
    while True:
        cores = {}
        for j, g in enumerate(game.guarantees):
            core = _env_buchi(game, losing - (g | game.failures) - below, game.assumptions,
                              avoid, frozenset(below))
            if core:
                cores[j] = frozenset(core)
        attr = _env_pre_layers(game, below.union(*cores.values()), losing, avoid)
        new = set(attr) - below
        if not new:
            return rank, layers
        for s in new:
            rank[s] = len(layers)
        layers.append(_Layer(frozenset(below), cores, attr))
        below |= new


class _Play:
    """The environment's layered strategy played against a curious controller (it takes a
    move to a state the play has not seen, an action it has not played first).  Every choice
    depends on (state, guarantee kept false, next assumption owed) only, so the play closes
    into a loop as soon as that triple repeats; layers never go up, so the loop lies in one
    core and keeps its guarantee false."""

    def __init__(self, game: ExplicitGame, rank: dict[int, int], layers: list[_Layer],
                 avoid: frozenset[int]) -> None:
        self.game, self.rank, self.layers, self.avoid = game, rank, layers, avoid
        self._towards: dict[tuple[int, int, int], tuple[set[int], dict[int, int]]] = {}

    def towards(self, k: int, j: int, i: int) -> tuple[set[int], dict[int, int]]:
        """Targets of assumption ``i`` in core ``j`` of layer ``k`` and the attractor."""
        if (k, j, i) not in self._towards:
            L = self.layers[k]
            ok = set(L.cores[j] | L.below)
            target = {t for t in L.cores[j] if t in self.game.assumptions[i]
                      and _env_can_stay(self.game, t, ok, self.avoid)}
            self._towards[(k, j, i)] = (target, _env_pre_layers(
                self.game, target | set(L.below), ok, self.avoid))
        return self._towards[(k, j, i)]

    def run(self, start: int) -> tuple[list[Step], int, list[int]]:
        """The steps, where the loop starts, and the guarantee kept false before each step."""
        game, n = self.game, len(self.game.assumptions)
        steps: list[Step] = []
        kept: list[int] = []
        seen: dict[tuple[int, int, int], int] = {}
        visited, played = {start}, set()
        s, i, j = start, 0, -1
        while len(steps) < 4 * MAX_STEPS:
            L = self.layers[self.rank[s]]
            if s not in L.cores.get(j, frozenset()):
                j = min((c for c, core in L.cores.items() if s in core), default=-1)
            owed = 0
            if j >= 0:
                while s in self.towards(self.rank[s], j, i)[0] and owed < n:
                    i, owed = (i + 1) % n, owed + 1
            if (s, j, i) in seen:
                return steps, seen[(s, j, i)], kept
            seen[(s, j, i)] = len(steps)
            if j < 0:
                allowed, layer = None, L.attr
            else:
                allowed = set(L.cores[j] | L.below)
                layer = ({t: 0 for t in allowed} if owed == n
                         else self.towards(self.rank[s], j, i)[1])
            st = _move(game, layer, s, allowed=allowed, avoid=self.avoid)
            if st is None:
                break
            if st.by_controller:
                fresh = sorted((a in played, a, t) for a, t in game.edges[s]
                               if a in game.controllable and t not in visited
                               and t not in self.avoid and t in self.rank
                               and (allowed is None or t in allowed))
                if fresh:
                    st = Step(s, fresh[0][1], fresh[0][2], True, st.alternatives)
            steps.append(st)
            kept.append(j)
            visited.add(st.target)
            played.add(st.action)
            s = st.target
        return steps, len(steps), kept


def _liveness_play(spec: GameSpec, game: ExplicitGame, losing: set[int], dead: set[int]
                   ) -> list[str] | None:
    """The lasso keeping one guarantee false forever, or ``None`` if the layers do not reach
    the initial state."""
    avoid = frozenset(dead)
    rank, layers = _layers(game, losing - dead, avoid)
    if game.initial not in rank:
        return None
    steps, cut, kept = _Play(game, rank, layers, avoid).run(game.initial)
    name = {j: show_formula(g) for j, g in enumerate(spec.guarantees)}
    p = Printer(spec, game)
    if steps and steps[-1].target in dead:
        # the controller's choices led into the safety attractor: the play ends in a dead end
        steps[-1] = _with_note(steps[-1], _violation(spec, game, steps[-1]))
        blocked = sorted({name[j] for j in kept if j in name})
        head = ("the environment keeps " + (", ".join(blocked) or "the guarantees")
                + " false as long as the controller tries, then forces a dead end:")
        return [head, p.initially(), *(p.step(n, st) for n, st in enumerate(steps, 1)),
                "  the last step ends the play (a violated property or a state without moves)."]
    loop_j = kept[cut] if cut < len(kept) else -1
    goal = name.get(loop_j, "true")
    if spec.assumptions:
        owed = ", ".join(show_formula(a) for a in spec.assumptions)
        head = (f"the environment keeps guarantee {goal} false forever (a liveness loss), "
                f"while making every assumption hold again and again ({owed}):")
    else:
        head = (f"the environment keeps guarantee {goal} false forever (a liveness loss; "
                "the spec has no assumptions that would rule this play out):")
    out = [head, p.initially()]
    for n, st in enumerate(steps, 1):
        if n - 1 == cut:
            out.append("  then, forever:")
        out.append(p.step(n, st))
    others = sorted({name[j] for j in kept[:cut] if j >= 0 and j != loop_j and j in name})
    if others:
        out.append(f"  (before the loop it keeps {', '.join(others)} false instead, until the "
                   "controller's choices let it switch)")
    for label, a in zip((show_formula(f) for f in spec.assumptions), game.assumptions, strict=False):
        where = [str(n) for n, st in enumerate(steps, 1) if n > cut and st.target in a]
        out.append(f"  assumption {label} holds in the loop after step(s) {', '.join(where)}")
    out.append(f"  ... and the loop repeats: {goal} never holds, so the guarantee is "
               "never reached.")
    return out


def explain_losing(spec: GameSpec, game: ExplicitGame, win: frozenset[int]) -> str:
    """The explanation of why ``game.initial`` is losing (``win`` = the winning region)."""
    n = game.num_states
    losing = set(range(n)) - set(win)
    out = [losing_head(*losing_count(game, win))]
    dead = {s for s in range(n) if not game.edges[s]}
    dead |= {s for s in range(n) if not game.env[s]
             and not any(a in game.controllable for a, _ in game.edges[s])}
    play = _safety_play(spec, game, dead) or _liveness_play(spec, game, losing, dead)
    if play is not None:
        return "\n".join(out + play)
    why = ", while every assumption holds" if spec.assumptions else ""
    out.append("the environment wins by switching which guarantee it keeps false" + why
               + "; fluent values of some losing states:")
    p = Printer(spec, game)
    shown: list[str] = []
    for s in sorted(losing - {game.error} if game.error is not None else losing):
        vals = p.fluents(s)
        line = "  " + (", ".join(f"{f}={_tf(v)}" for f, v in vals.items()) or "(no fluents)")
        if line not in shown:
            shown.append(line)
    return "\n".join(out + shown[:10])
