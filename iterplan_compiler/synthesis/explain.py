"""Explanations for unrealizable specifications: losing states and a counter-strategy trace.

The environment wins from the initial state.  We report

* how many reachable game states are losing;
* if the environment can *force* a dead end (ERROR = a violated safety property, a deadlock,
  or a controller state without controllable moves): a shortest forcing trace, where at every
  controller-owned state all its alternatives are listed (they all lose too);
* otherwise, a guarantee ``G_j`` the environment can avoid forever: a forcing prefix into a
  trap that avoids ``G_j`` (and failures), plus a cycle inside it, and which assumptions that
  cycle visits (if it misses one, the environment's real strategy must interleave them —
  GR(1) counter-strategies are not always a single lasso).
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
        avoid = losing - g
        # trap: greatest set inside avoid where the environment can stay
        trap = set(avoid)
        while True:
            keep = set()
            for s in trap:
                if game.env[s]:
                    if any(a not in game.controllable and t in trap for a, t in game.edges[s]):
                        keep.add(s)
                else:
                    cs = [t for a, t in game.edges[s] if a in game.controllable]
                    if cs and all(t in trap for t in cs):
                        keep.add(s)
            if keep == trap:
                break
            trap = keep
        if not trap:
            continue
        attr = _env_pre_layers(game, trap, losing)
        if game.initial not in attr:
            continue
        out.append(f"the environment can keep the play away from guarantee #{j + 1} forever:")
        out += _forcing_trace(spec, game, attr, game.initial, trap)
        # a cycle inside the trap, following the environment's first staying move
        s = next(iter(sorted(trap))) if game.initial not in trap else game.initial
        seen: list[int] = []
        while s not in seen and len(seen) < MAX_STEPS:
            seen.append(s)
            nxt = sorted(t for a, t in game.edges[s] if t in trap
                         and (a not in game.controllable) == game.env[s])
            s = nxt[0]
        cyc = seen[seen.index(s):] if s in seen else seen
        out.append(f"  ... and then it can loop through {len(cyc)} state(s) avoiding it:")
        out += [f"    {describe_state(spec, game, c)}" for c in cyc]
        missed = [i + 1 for i, a in enumerate(game.assumptions) if not (set(cyc) & a)]
        if missed and spec.assumptions:
            out.append(f"  (this loop misses assumption(s) {missed}; the environment's "
                       "strategy must also satisfy them elsewhere in the losing region)")
        return "\n".join(out)
    out.append("the environment wins by alternating between assumption-satisfying loops that "
               "avoid some guarantee; losing states (first 10):")
    out += [f"  {describe_state(spec, game, s)}" for s in sorted(losing)[:10]]
    return "\n".join(out)
