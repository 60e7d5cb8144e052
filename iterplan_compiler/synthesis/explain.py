"""Explanations for unrealizable specifications: losing states and a counter-strategy trace.

The environment wins from the initial state.  We report

* how many reachable game states are losing;
* if the environment can *force* a dead end (ERROR = a violated safety property, a deadlock,
  or a controller state without controllable moves): a shortest forcing trace, where at every
  controller-owned state all its alternatives are listed (they all lose too);
* otherwise, a guarantee ``G_j`` the environment can avoid forever *while satisfying every
  assumption*: the largest set of losing non-``G_j`` states where the environment can stay and
  still force visits to every ``A_i`` (a generalised Büchi game for the environment), a
  forcing prefix into it, and one round of the environment's loop visiting each ``A_i``;
* if no single guarantee works (the environment must adapt which guarantee it blocks), the
  first losing states.
"""

from __future__ import annotations

from iterplan_compiler.synthesis.encode import GameSpec
from iterplan_compiler.synthesis.explicit import ExplicitGame

MAX_STEPS = 25


def describe_state(spec: GameSpec, game: ExplicitGame, s: int) -> str:
    """``Comp=state, ..., fluent=true`` for game state ``s`` (ERROR for the error state)."""
    tup = game.tuples[s] if s < len(game.tuples) else None
    if tup is None:
        return "ERROR"
    parts = []
    nbody = spec.num_plant + spec.num_safety
    for k, c in enumerate(spec.components[:nbody]):
        st = tup[k]
        label = c.state_names[st] if c.state_names and st < len(c.state_names) else str(st)
        parts.append(f"{c.name or 'P' + str(k)}={label}")
    for k, fname in enumerate(spec.fluent_names):
        parts.append(f"{fname}={'true' if tup[nbody + k] == 1 else 'false'}")
    return "(" + ", ".join(parts) + ")"


def _env_pre_layers(game: ExplicitGame, target: set[int], within: set[int]) -> dict[int, int]:
    """Environment attractor of ``target`` inside ``within``: state -> layer index."""
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
                cs = [t for a, t in game.edges[s] if a in ctrl]
                if all(t in layer for t in cs):  # includes "no controllable move" (dead end)
                    new.append(s)
        for s in new:
            layer[s] = k
            changed = True
    return layer


def _forcing_trace(spec: GameSpec, game: ExplicitGame, layer: dict[int, int], start: int,
                   stop: set[int]) -> list[str]:
    ctrl = game.controllable
    lines = []
    s = start
    for _ in range(MAX_STEPS):
        if s in stop:
            break
        if game.env[s]:
            a, t = min((a, t) for a, t in game.edges[s] if a not in ctrl and t in layer
                       and layer[t] < layer[s])
            lines.append(f"  {describe_state(spec, game, s)}  environment plays {a}")
        else:
            moves = sorted((a, t) for a, t in game.edges[s] if a in ctrl)
            if not moves:
                lines.append(f"  {describe_state(spec, game, s)}  controller has no move")
                return lines
            a, t = min(moves, key=lambda m: (layer.get(m[1], 1 << 30), m[0]))
            alts = ", ".join(sorted({x for x, _ in moves}))
            lines.append(f"  {describe_state(spec, game, s)}  controller must pick one of "
                         f"{{{alts}}}; all lose, e.g. {a}")
        s = t
    lines.append(f"  {describe_state(spec, game, s)}")
    return lines


def _env_can_stay(game: ExplicitGame, s: int, Z: set[int]) -> bool:
    ctrl = game.controllable
    if game.env[s]:
        return any(a not in ctrl and t in Z for a, t in game.edges[s])
    cs = [t for a, t in game.edges[s] if a in ctrl]
    return bool(cs) and all(t in Z for t in cs)


def _env_buchi(game: ExplicitGame, region: set[int], assumptions: list[frozenset[int]]
               ) -> set[int]:
    """Largest ``Z ⊆ region`` where the environment can stay forever and force a visit to
    every assumption set again and again (generalised Büchi for the environment)."""
    Z = set(region)
    while True:
        new = set(Z)
        for a in assumptions:
            target = {s for s in Z if s in a and _env_can_stay(game, s, Z)}
            new &= set(_env_pre_layers(game, target, Z))
        if new == Z:
            return Z
        Z = new


def _step(game: ExplicitGame, layer: dict[int, int], s: int, within: set[int] | None = None
          ) -> int:
    """The environment's move (or the controller's first alternative) decreasing ``layer``."""
    ctrl = game.controllable
    ok = within if within is not None else layer
    if game.env[s]:
        cands = [(layer.get(t, 1 << 30), a, t) for a, t in game.edges[s]
                 if a not in ctrl and t in ok]
    else:
        cands = [(layer.get(t, 1 << 30), a, t) for a, t in game.edges[s] if a in ctrl]
    if not cands:  # defensive: callers only step from states with a move
        raise ValueError(f"state {s} has no move")
    return min(cands)[2]


def _move_text(spec: GameSpec, game: ExplicitGame, layer: dict[int, int], s: int,
               within: set[int] | None = None) -> str:
    ctrl = game.controllable
    ok = within if within is not None else layer
    if game.env[s]:
        _, a, _ = min((layer.get(t, 1 << 30), a, t) for a, t in game.edges[s]
                      if a not in ctrl and t in ok)
        return f"{describe_state(spec, game, s)}  environment plays {a}"
    alts = ", ".join(sorted({a for a, _ in game.edges[s] if a in ctrl}))
    return f"{describe_state(spec, game, s)}  controller picks one of {{{alts}}} (all lose)"


def explain_losing(spec: GameSpec, game: ExplicitGame, win: frozenset[int]) -> str:
    """Text explaining why ``game.initial`` is losing (``win`` = winning region)."""
    n = game.num_states
    losing = set(range(n)) - set(win)
    out = [f"unrealizable: the initial state is losing ({len(losing)} of {n} reachable game "
           f"states are losing)"]
    dead = {s for s in range(n) if not game.edges[s]}
    dead |= {s for s in range(n) if not game.env[s]
             and not any(a in game.controllable for a, _ in game.edges[s])}
    attr = _env_pre_layers(game, dead, set(range(n)))
    if game.initial in attr:
        out.append("the environment can force a dead end (ERROR = safety violation, or a "
                   "state where the controller cannot move):")
        out += _forcing_trace(spec, game, attr, game.initial, dead)
        return "\n".join(out)
    goals = [g | game.failures for g in game.guarantees]
    for j, g in enumerate(goals):
        core = _env_buchi(game, losing - g - dead, game.assumptions)
        if not core:
            continue
        attr = _env_pre_layers(game, core, losing)
        if game.initial not in attr:
            continue
        out.append(f"the environment can keep the play away from guarantee #{j + 1} forever "
                   "while satisfying every assumption:")
        out += _forcing_trace(spec, game, attr, game.initial, core)
        s = game.initial
        while s not in core:  # replay the forcing prefix to know where the loop starts
            s = _step(game, attr, s)
        out.append(f"  then, inside {len(core)} state(s) that avoid it, the environment "
                   "visits each assumption in turn:")
        for i, a in enumerate(game.assumptions):
            target = {t for t in core if t in a and _env_can_stay(game, t, core)}
            lay = _env_pre_layers(game, target, core)
            steps = 0
            while s not in target and s in lay and steps < MAX_STEPS:
                out.append("    " + _move_text(spec, game, lay, s))
                s = _step(game, lay, s)
                steps += 1
            if s not in target:
                break
            label = f"assumption #{i + 1} holds here" if spec.assumptions else "loop point"
            out.append(f"    {describe_state(spec, game, s)}  <- {label}")
            # one move that stays inside the core
            stay = {t: 0 for t in core}
            out.append("    " + _move_text(spec, game, stay, s, within=core))
            s = _step(game, stay, s, within=core)
        out.append("    ... and repeats, so the guarantee is never reached.")
        return "\n".join(out)
    out.append("the environment wins by alternating between assumption-satisfying loops that "
               "avoid some guarantee; losing states (first 10):")
    out += [f"  {describe_state(spec, game, s)}" for s in sorted(losing)[:10]]
    return "\n".join(out)
