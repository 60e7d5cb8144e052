"""Fluent-aligned state codes for the leaf machines of a game (a renumbering, nothing more).

A safety automaton of an LTL property over fluents (SYNTECH15's ``G3_min``, ``G9_min``, ...)
*tracks* the fluents it mentions: its state determines their values.  With its states
numbered as the minimiser left them, the binary code of a state is a scrambled function of
those values, and every machine tracking ``BALANCER_FWD`` carries its own scrambled copy of
it; the BDD of the reachable set must then spell out, for every machine, which codes go with
which values of the other machines' copies.  This module numbers each machine's states so
that the code *is* ``(feature bits, residual index, error bit)``: bit ``i < m`` of a state's
code is the value of the machine's ``i``-th tracked feature, the bits above number the
states that share the feature values.  ``GameSpec.bit_keys`` names each bit's feature, and
:class:`symbolic_game.SymbolicGame` gives all bits with the same key *one shared variable*.

A *feature* of machine ``M`` with key ``<a|T>v`` is a partition ``φ : Q → {0, 1}`` with
``φ(init) = v`` such that every ``a``-transition enters ``φ = 1``, every transition on an
action of ``T`` enters ``φ = 0`` and every other transition keeps ``φ``: ``φ`` is the value
of the fluent ``<{a}, T> initially v`` along every run.  ``T`` is guessed as the actions
whose targets never meet ``a``'s; a guess that admits no such ``φ`` is dropped.

Why sharing is sound: two machines with the same key track the same fluent (same ``a``,
same ``T`` — a subset of both alphabets —, same initial value; an action outside a machine's
alphabet keeps its ``φ`` and is in neither ``T`` nor ``{a}``), so their feature bits are
equal in every reachable product state; the shared-variable encoding drops only unreachable
(inconsistent) states, and every reachable edge is kept.  The renumbering itself is an
isomorphism of each machine, so the game, its winning region and its controller are
unchanged (the controller's states are numbered by its own enumeration, never by these
codes).  A fluent monitor (whose state *is* its value) is never renumbered, only keyed.

Codes unused by a state become isolated padding states (no transitions in or out, so they
are never reachable).  With ERROR moves the top bit is an *error bit*: ERROR keeps the code
``num_states`` = the error bit alone, and every code with it set counts as ERROR, so the
game's ``error`` set is one variable per machine instead of a scattered cube.  A machine is
recoded only when its width grows by at most :data:`MAX_EXTRA_BITS`.

Measured on SYNTECH15 GyroLTL_637 (issue 12; 39 of 41 components keyed, 121 → 130 bits of
which ~20 shared): reachability 2 308 414 states in a 28 k-node BDD, 17 s CPU, against
> 770 k nodes and no fixpoint after 100 s CPU with the plain codes.
"""

from __future__ import annotations

from dataclasses import replace

from iterplan_compiler.ir.lts import ERROR, LTS, TAU, make_lts
from iterplan_compiler.symbolic.bdd import bits_for
from iterplan_compiler.synthesis.encode import GameSpec

#: a recoded machine may use this many more bits than its plain binary code
MAX_EXTRA_BITS = 1

#: the key of a recoded machine's error bit (all codes with it set are ERROR)
ERROR_BIT = "#error"

Feature = tuple[str, tuple[int, ...]]  # (key: the fluent <{a}, T> and its initial value, φ)


def _find(parent: list[int], x: int) -> int:
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


def _feature(c: LTS, a: str, targets: dict[str, set[int]]) -> Feature | None:
    """The fluent ``<{a}, T>`` that ``c`` tracks (``T`` guessed, module doc), or None."""
    mine = targets[a]
    resets = frozenset(b for b, ts in targets.items() if b != a and ts and not ts & mine)
    parent = list(range(c.num_states))
    for s, b, t in c.transitions:
        if t != ERROR and b != a and b not in resets:
            rs, rt = _find(parent, s), _find(parent, t)
            if rs != rt:
                parent[rs] = rt
    value: dict[int, int] = {}
    for v, acts in ((1, (a,)), (0, tuple(resets))):
        for b in acts:
            for t in targets[b]:
                r = _find(parent, t)
                if value.setdefault(r, v) != v:
                    return None
    phi = tuple(value.get(_find(parent, s), 0) for s in range(c.num_states))
    if not 0 < sum(phi) < len(phi):
        return None
    return f"<{a}|{','.join(sorted(resets))}>{phi[c.initial]}", phi


def features(c: LTS) -> list[Feature]:
    """The distinct features of ``c`` (module doc)."""
    targets: dict[str, set[int]] = {a: set() for a in c.alphabet}
    for _, b, t in c.transitions:
        if t != ERROR and b != TAU:
            targets[b].add(t)
    out: list[Feature] = []
    seen: set[tuple[int, ...]] = set()
    for a in sorted(targets):
        if not targets[a]:
            continue
        f = _feature(c, a, targets)
        if f is None or f[1] in seen or tuple(1 - v for v in f[1]) in seen:
            continue
        seen.add(f[1])
        out.append(f)
    return out


def _layout(c: LTS, feats: list[Feature]) -> tuple[list[int], int] | None:
    """Codes per state and the width (error bit included), or None if over the budget."""
    m = len(feats)
    classes: dict[int, list[int]] = {}
    for s in range(c.num_states):
        classes.setdefault(sum(phi[s] << i for i, (_, phi) in enumerate(feats)), []).append(s)
    need = max(len(ss) for ss in classes.values())
    r = bits_for(need) if need > 1 else 0
    width = m + r + (1 if c.has_error else 0)
    if width > bits_for(c.num_states + (1 if c.has_error else 0)) + MAX_EXTRA_BITS:
        return None
    code = [0] * c.num_states
    for v, ss in classes.items():
        for idx, s in enumerate(ss):
            code[s] = v | (idx << m)
    return code, width


def codes(c: LTS) -> tuple[list[int], int, list[Feature]] | None:
    """Per state its code, the code width (error bit included) and the features whose
    values are the low bits; None when ``c`` tracks no feature within the bit budget."""
    feats = features(c)
    while feats:
        lay = _layout(c, feats)
        if lay is not None:
            return lay[0], lay[1], feats
        feats = feats[:-1]
    return None


def recode_machine(c: LTS) -> tuple[LTS, tuple[str | None, ...]] | None:
    """``c`` renumbered to fluent-aligned codes and each bit's key (None: a residual bit),
    or None when ``c`` tracks no feature within the bit budget."""
    lay = codes(c)
    if lay is None:
        return None
    code, width, feats = lay
    # with ERROR moves the top bit is the error bit: ERROR is code 2^(width-1) = num_states
    n = 1 << (width - 1 if c.has_error else width)
    trans = [(code[s], a, ERROR if t == ERROR else code[t]) for s, a, t in c.transitions]
    names = None
    if c.state_names is not None:
        names = ["pad"] * n
        for s, nm in enumerate(c.state_names):
            names[code[s]] = nm
    out = make_lts(c.name, n, trans, c.alphabet, code[c.initial],
                   (code[s] for s in c.end_states), names)
    keys = tuple(a for a, _ in feats) + (None,) * (width - len(feats) - c.has_error)
    if c.has_error:
        keys += (ERROR_BIT,)
    return out, keys


def _monitor_keys(c: LTS) -> tuple[LTS, tuple[str | None, ...]] | None:
    """A fluent monitor is never renumbered (its state *is* the fluent's value); its bit gets
    the key of the feature whose partition is that value."""
    for a, phi in features(c):
        if phi == (0, 1):
            return c, (a,)
    return None


def recode_leaves(spec: GameSpec) -> GameSpec:
    """``spec`` with every component that tracks features recoded (module doc) and
    ``bit_keys`` set; ``spec`` itself when no component changes."""
    comps = list(spec.components)
    keys: list[tuple[str | None, ...]] = []
    changed = False
    nbody = spec.num_plant + spec.num_safety
    for k, c in enumerate(comps):
        rec = recode_machine(c) if k < nbody else _monitor_keys(c)
        if rec is None:
            keys.append((None,) * bits_for(c.num_states + (1 if c.has_error else 0)))
            continue
        comps[k], kk = rec
        keys.append(kk)
        changed = True
    if not changed:
        return spec
    return replace(spec, components=tuple(comps), bit_keys=tuple(keys))
