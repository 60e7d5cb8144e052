"""Small builders shared by the LTS-algorithm tests (not a test module)."""

from __future__ import annotations

from iterplan_compiler.ir.lts import ERROR, LTS, make_lts

E = ERROR


def cycle(name: str, *labels: str) -> LTS:
    """``NAME = (l0 -> l1 -> ... -> NAME)``."""
    n = len(labels)
    return make_lts(name, n, [(i, a, (i + 1) % n) for i, a in enumerate(labels)])


def lts(name: str, n: int, trans, alphabet=(), end=(), initial: int = 0) -> LTS:
    return make_lts(name, n, trans, alphabet, initial, end)


def moves(m: LTS, state: int) -> list[tuple[str, int]]:
    return sorted((a, t) for s, a, t in m.transitions if s == state)
