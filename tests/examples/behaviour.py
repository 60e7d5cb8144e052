"""Behaviour checks on flown missions, shared by the example tests (reads event logs only)."""

from __future__ import annotations

from iterplan_compiler.experiments.missions import LogEvent


def cells(log: list[LogEvent], label: str) -> list[int]:
    return [e.cell for e in log if e.label == label]


def check_fire_patrol(log: list[LogEvent], grid) -> None:
    """Every patrol cell visited, nothing else visited, a photo exactly where fire was reported
    (fire cells that are in P), and each photo taken right at the cell where yes.fire came."""
    patrol = {int(c) for c in grid.sensors["inP"]}
    fire = {int(c) for c in grid.sensors["fire"]}
    visited = set(cells(log, "arrived"))
    assert visited == patrol, (sorted(visited ^ patrol))
    photos = cells(log, "take.photo")
    assert sorted(photos) == sorted(fire & patrol)
    # photo follows yes.fire at the same arrival
    last_arrival = None
    fire_here = False
    for e in log:
        if e.label == "arrived":
            last_arrival, fire_here = e.cell, False
        elif e.label == "yes.fire":
            fire_here = True
        elif e.label == "take.photo":
            assert fire_here and e.cell == last_arrival


def check_cover(log: list[LogEvent], grid) -> None:
    region = {int(c) for c in grid.sensors["cover"]}
    assert set(cells(log, "arrived")) == region


def check_ordered_patrol(log: list[LogEvent], grid, n: int) -> None:
    """visited.p.i events come in the order 0, 1, ..., n-1, 0, ... and each at p.i's cell."""
    visits = [e for e in log if e.label.startswith("visited.p.")]
    assert len(visits) >= n
    for k, e in enumerate(visits):
        i = int(e.label.rsplit(".", 1)[1])
        assert i == k % n, [v.label for v in visits]
        assert e.cell == int(grid.sensors[f"p.{i}"][0])
