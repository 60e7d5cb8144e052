"""Independent slow scalar Dubins reference (float64, textbook alpha/beta/d formulation).

Deliberately written differently from the vectorised kernel (normalised distances, angles from
atan2, explicit word formulas) and checked itself by integrating each path and comparing the end
pose with the goal.
"""

from __future__ import annotations

import math

TWO_PI = 2 * math.pi


def _mod(a: float) -> float:
    m = a % TWO_PI
    return 0.0 if m > TWO_PI - 1e-9 else m


def words(q0, q1, r):
    """All feasible CSC words: {name: (t, p, q)} with t, q in radians and p normalised length."""
    dx, dy = q1[0] - q0[0], q1[1] - q0[1]
    d = math.hypot(dx, dy) / r
    th = _mod(math.atan2(dy, dx)) if d > 0 else 0.0
    a, b = _mod(q0[2] - th), _mod(q1[2] - th)
    sa, sb, ca, cb = math.sin(a), math.sin(b), math.cos(a), math.cos(b)
    cab = math.cos(a - b)
    out = {}
    p2 = 2 + d * d - 2 * cab + 2 * d * (sa - sb)
    if p2 >= 0:
        tmp = math.atan2(cb - ca, d + sa - sb)
        out["LSL"] = (_mod(-a + tmp), math.sqrt(p2), _mod(b - tmp))
    p2 = 2 + d * d - 2 * cab + 2 * d * (sb - sa)
    if p2 >= 0:
        tmp = math.atan2(ca - cb, d - sa + sb)
        out["RSR"] = (_mod(a - tmp), math.sqrt(p2), _mod(-b + tmp))
    p2 = -2 + d * d + 2 * cab + 2 * d * (sa + sb)
    if p2 >= 0:
        p = math.sqrt(p2)
        tmp = math.atan2(-ca - cb, d + sa + sb) - math.atan2(-2.0, p)
        out["LSR"] = (_mod(-a + tmp), p, _mod(-b + tmp))
    p2 = d * d - 2 + 2 * cab - 2 * d * (sa + sb)
    if p2 >= 0:
        p = math.sqrt(p2)
        tmp = math.atan2(ca + cb, d - sa - sb) - math.atan2(2.0, p)
        out["RSL"] = (_mod(a - tmp), p, _mod(b - tmp))
    return out


def csc_length(q0, q1, r):
    """Shortest CSC length (metres) from pose q0 to pose q1 (x, y, heading radians)."""
    ws = words(q0, q1, r)
    return min(r * (t + p + q) for t, p, q in ws.values())


def integrate(q0, word, tpq, r, steps=400):
    """Fly the word from q0 and return the end pose (for checking the formulas)."""
    x, y, h = q0
    t, p, q = tpq
    for seg, amount in zip(word, (t, p * r, q), strict=False):
        for _ in range(steps):
            if seg == "S":
                ds = amount / steps
                x += ds * math.cos(h)
                y += ds * math.sin(h)
            else:
                dh = (amount / steps) * (1 if seg == "L" else -1)
                # exact arc step of angle dh on radius r
                cx, cy = (x - r * math.sin(h), y + r * math.cos(h)) if seg == "L" else (
                    x + r * math.sin(h), y - r * math.cos(h))
                h += dh
                x, y = (cx + r * math.sin(h), cy - r * math.cos(h)) if seg == "L" else (
                    cx - r * math.sin(h), cy + r * math.cos(h))
    return x, y, h
