"""A finished run's output folder (``iterc run --out``) as the page's replay data.

Reads ``track.csv`` (t, lat, lon, alt, ...), ``events.csv`` (t, kind, label, state, east, north,
alt, cell) and ``summary.json``; with the run's map (``--map``) the grid and sensor layers are
drawn too and arrivals are shaded on their cells.  The files do not say which cell the iterator
offered at each step, so the replay shows ``|D|`` (counted from ``remove.next``/``reset``), the
arrivals, photos, the controller state and the event log over time, not ``n`` itself.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

from iterplan_compiler.view.snapshot import map_message


class ReplayError(ValueError):
    pass


def _float(text: str) -> float:
    v = float(text)
    if not math.isfinite(v):
        raise ValueError(text)
    return v


def _monotonic(rows: list[list]) -> None:
    """Mission time restarts at 0 when the controller starts (take-off rows come first, timed
    from the vehicle's start): shift each earlier stretch so the times only grow (take-off gets
    negative mission times).  Rows stay in file order, which is the order they happened in."""
    for i in range(len(rows) - 1, 0, -1):
        if rows[i][0] < rows[i - 1][0] - 1e-9:
            shift = rows[i][0] - rows[i - 1][0]
            for r in rows[:i]:
                r[0] = round(r[0] + shift, 3)


def load_run(run_dir: str | Path, grid: Any = None) -> dict:
    run = Path(run_dir)
    if not run.is_dir():
        raise ReplayError(f"{run} is not a folder")
    files = {n: run / n for n in ("track.csv", "events.csv", "summary.json")}
    missing = [n for n, p in files.items() if not p.is_file()]
    if missing:
        raise ReplayError(f"{run} lacks {', '.join(missing)} (not an `iterc run --out` folder?)")
    try:
        summary = json.loads(files["summary.json"].read_text())
        track = []
        with open(files["track.csv"], newline="") as fh:
            for row in csv.DictReader(fh):
                track.append([_float(row["t"]), round(_float(row["lat"]), 7),
                              round(_float(row["lon"]), 7), _float(row["alt"]),
                              _float(row["east"]), _float(row["north"])])
        events: list[list[Any]] = []
        with open(files["events.csv"], newline="") as fh:
            for row in csv.DictReader(fh):
                events.append([_float(row["t"]), row["kind"], row["label"], int(row["state"]),
                               row.get("cell", ""), _float(row["east"]), _float(row["north"])])
    except (OSError, ValueError, KeyError, json.JSONDecodeError) as exc:
        raise ReplayError(f"{run}: cannot read the run: {exc}") from None
    if not track:
        raise ReplayError(f"{run}/track.csv has no points")
    _monotonic(track)
    _monotonic(events)
    # ENU -> lat/lon: from the track's own columns (a linear fit is exact for the local frame).
    ax, bx = min(track, key=lambda r: r[4]), max(track, key=lambda r: r[4])
    ay, by = min(track, key=lambda r: r[5]), max(track, key=lambda r: r[5])
    kx = (bx[2] - ax[2]) / (bx[4] - ax[4]) if bx[4] - ax[4] > 1 else 0.0
    ky = (by[1] - ay[1]) / (by[5] - ay[5]) if by[5] - ay[5] > 1 else 0.0
    lon_a, x_a, lat_a, y_a = ax[2], ax[4], ay[1], ay[5]

    def ll(x: float, y: float) -> list[float]:
        if grid is not None:
            la, lo = grid.to_latlon(x, y)
            return [round(la, 7), round(lo, 7)]
        return [round(lat_a + (y - y_a) * ky, 7), round(lon_a + (x - x_a) * kx, 7)]

    name_to_cell: dict[str, int] = {}
    if grid is not None:
        from iterplan_compiler.runtime.mapfile import parse_cell_name
        for e in events:
            if e[4] and e[4] not in name_to_cell:
                try:
                    name_to_cell[e[4]] = int(parse_cell_name(grid, e[4]))
                except Exception:  # noqa: BLE001 - a cell of another map: not shaded
                    name_to_cell[e[4]] = -1
    arrivals, photos = [], []
    for t, kind, label, _state, cell, x, y in events:
        if kind == "p" and label.split(" ")[0] == "arrived":
            c = name_to_cell.get(cell, -1)
            arrivals.append([t, *ll(x, y), c if c >= 0 else None, cell])
        elif kind == "c" and label == "take.photo":
            photos.append([t, *ll(x, y), cell])
    lats = [r[1] for r in track]
    lons = [r[2] for r in track]
    t0 = min(0.0, track[0][0])
    t1 = max(track[-1][0], events[-1][0] if events else 0.0)
    return {
        "title": f"{summary.get('controller', 'run')} (replay of {run.name})",
        "map": map_message(grid, f"{summary.get('controller', 'run')} (replay of {run.name})")
        if grid is not None else None,
        "home": [lats[0], lons[0]],
        "bounds": [[min(lats), min(lons)], [max(lats), max(lons)]],
        "track": [r[:4] for r in track], "events": [e[:5] for e in events],
        "arrivals": arrivals, "photos": photos, "summary": summary,
        "speed": summary.get("speed_mps", 0.0), "t0": t0, "t1": t1,
    }
