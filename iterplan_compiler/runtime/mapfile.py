"""Map files and cell-set files: :func:`load_map` (the JSON map schema of docs/runtime.md) and
the cell-set readers it uses (GeoJSON, text lists, cell names, sensor rules).  Split from
:mod:`.grid` (which still exports these names)."""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import ValidationError

from iterplan_compiler.runtime.grid import (
    DerivedSensor,
    DynamicSensor,
    GridMap,
    MapError,
    compass_to_math,
)
from iterplan_compiler.runtime.mapschema import (
    _MAP_ADAPTER,
    _GPolygon,
    _HomeCell,
    json_path,
    schema_error,
    validate_geojson,
)

# -- files ------------------------------------------------------------------------------------

def _geojson_geometries(obj: dict) -> list[dict]:
    t = obj.get("type")
    if t == "FeatureCollection":
        return [g for f in obj.get("features", []) for g in _geojson_geometries(f)]
    if t == "Feature":
        return _geojson_geometries(obj.get("geometry") or {})
    if t == "GeometryCollection":
        return [g for sub in obj.get("geometries", []) for g in _geojson_geometries(sub)]
    if t in ("Polygon", "MultiPolygon", "Point", "MultiPoint"):
        return [obj]
    raise MapError(f"unsupported GeoJSON object {t!r}")


def cells_from_geojson(grid: GridMap, obj: dict) -> np.ndarray:
    """Cells covered by GeoJSON polygons (centre inside; holes subtracted) or containing points."""
    out: list[np.ndarray] = []
    for geom in _geojson_geometries(obj):
        t, coords = geom["type"], geom.get("coordinates", [])
        if t in ("Point", "MultiPoint"):
            pts = np.asarray([coords] if t == "Point" else coords, dtype=np.float64).reshape(-1, 2)
            x, y = grid.to_enu(pts[:, 1], pts[:, 0])
            ids = np.atleast_1d(grid.cell_at(x, y))
            out.append(ids[ids >= 0])
            continue
        polys = [coords] if t == "Polygon" else coords
        for rings in polys:
            shell = np.asarray(rings[0], dtype=np.float64)
            x, y = grid.to_enu(shell[:, 1], shell[:, 0])
            ids = grid.cells_in_polygon(np.column_stack([x, y]))
            for hole in rings[1:]:
                h = np.asarray(hole, dtype=np.float64)
                hx, hy = grid.to_enu(h[:, 1], h[:, 0])
                ids = np.setdiff1d(ids, grid.cells_in_polygon(np.column_stack([hx, hy])))
            out.append(ids)
    return np.unique(np.concatenate(out)) if out else np.zeros(0, dtype=np.int64)


def cells_from_text(grid: GridMap, text: str) -> np.ndarray:
    """Simple cell lists: one entry per line, ``#`` comments.  Each entry is a cell name (``C5``),
    ``col,row`` (0-based integers) or ``lat,lon`` (decimal degrees, detected by a dot)."""
    ids: list[int] = []
    for lineno, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        parts = [p for p in line.replace(";", ",").replace(" ", ",").split(",") if p]
        try:
            if len(parts) == 1:
                ids.append(parse_cell_name(grid, parts[0]))
            elif "." in line:
                lat, lon = float(parts[0]), float(parts[1])
                ids.append(int(grid.cell_at(*grid.to_enu(lat, lon))))
            else:
                col, row = int(parts[0]), int(parts[1])
                ids.append(row * grid.cols + col if 0 <= col < grid.cols and 0 <= row < grid.rows
                           else -1)
        except (ValueError, IndexError):
            raise MapError(f"line {lineno}: cannot read a cell from {raw.strip()!r}") from None
        if ids[-1] < 0:
            raise MapError(f"line {lineno}: {raw.strip()!r} is outside the map")
    return np.unique(np.asarray(ids, dtype=np.int64))


def parse_cell_name(grid: GridMap, name: str) -> int:
    """``C5`` -> cell id (inverse of :meth:`GridMap.cell_name`)."""
    letters = "".join(ch for ch in name if ch.isalpha()).upper()
    digits = name[len(letters):]
    if not letters or not digits.isdigit() or not name[:len(letters)].isalpha():
        raise ValueError(name)
    col = 0
    for ch in letters:
        col = col * 26 + (ord(ch) - 64)
    col -= 1
    row = int(digits) - 1
    if not (0 <= col < grid.cols and 0 <= row < grid.rows):
        return -1
    return row * grid.cols + col


def _cell_spec(grid: GridMap, spec, base: Path) -> np.ndarray:
    """A sensor's cell set from a map-file entry (see :func:`load_map`)."""
    if isinstance(spec, list):
        return cells_from_text(grid, "\n".join(
            ",".join(str(v) for v in e) if isinstance(e, list) else str(e) for e in spec))
    if isinstance(spec, str):
        spec = {"file": spec}
    if not isinstance(spec, dict):
        raise MapError(f"cannot read a cell set from {spec!r}")
    if "type" in spec:  # inline GeoJSON
        validate_geojson(spec, "GeoJSON")
        return cells_from_geojson(grid, spec)
    if "cells" in spec:
        return _cell_spec(grid, spec["cells"], base)
    if "rect" in spec:  # [col0, row0, col1, row1], inclusive, 0-based
        c0, r0, c1, r1 = (int(v) for v in spec["rect"])
        if c1 >= grid.cols or r1 >= grid.rows:
            raise MapError(f"rect {[c0, r0, c1, r1]} reaches outside the {grid.cols} x "
                           f"{grid.rows} grid")
        cc, rr = np.meshgrid(np.arange(c0, c1 + 1), np.arange(r0, r1 + 1))
        return np.unique((rr * grid.cols + cc).ravel().astype(np.int64))
    if "random" in spec:  # {"random": fraction, "seed": n}: synthetic scenarios
        rng = np.random.default_rng(int(spec.get("seed", 0)))
        pick = rng.random(len(grid.cells)) < float(spec["random"])
        return grid.cells[pick]
    if "file" in spec:
        try:
            path = (base / spec["file"]).resolve()
            text = path.read_text(encoding="utf-8-sig")
        except (OSError, ValueError) as exc:  # ValueError: a NUL byte in the name
            why = getattr(exc, "strerror", None) or exc
            raise MapError(f"cannot read {spec['file'][:200]}: {why}") from None
        except UnicodeDecodeError as exc:
            raise MapError(f"{spec['file']}: not UTF-8 text (byte {exc.start})") from None
        if path.suffix in (".json", ".geojson"):
            try:
                obj = json.loads(text)
            except (ValueError, RecursionError) as exc:  # JSONDecodeError is a ValueError
                raise MapError(f"{spec['file']}: invalid JSON: {exc}") from None
            validate_geojson(obj, spec["file"])
            return cells_from_geojson(grid, obj)
        return cells_from_text(grid, text)
    raise MapError(f"cannot read a cell set from {spec!r}")


def parse_sensor_rules(data: dict, static: Iterable[str] = ()) -> tuple[
        dict[str, DynamicSensor], dict[str, DerivedSensor]]:
    """The ``"dynamic"`` and ``"derived"`` sections of a map file (see :func:`load_map`).

    ``static`` are the map's static sensor names: a dynamic sensor must be one of them (it
    limits their yes answers), a derived sensor must not (it has no static cells).  Raises
    :class:`MapError` with a readable message.
    """
    static = set(static)
    dynamic: dict[str, DynamicSensor] = {}
    derived: dict[str, DerivedSensor] = {}
    dyn = data.get("dynamic") or {}
    der = data.get("derived") or {}
    if not isinstance(dyn, dict) or not isinstance(der, dict):
        raise MapError("'dynamic' and 'derived' must be JSON objects keyed by sensor name")
    for name, spec in dyn.items():
        if name not in static:
            raise MapError(f"dynamic sensor {name!r} has no cells in 'sensors' "
                           f"(map sensors: {', '.join(sorted(static)) or 'none'})")
        if not isinstance(spec, dict) or set(spec) - {"yes_answers"}:
            raise MapError(f"dynamic sensor {name!r}: expected {{\"yes_answers\": K}}")
        k = spec.get("yes_answers", 1)
        if isinstance(k, bool) or not isinstance(k, int) or k < 1:
            raise MapError(f"dynamic sensor {name!r}: yes_answers must be an integer >= 1, "
                           f"not {k!r}")
        dynamic[str(name)] = DynamicSensor(k)
    for name, spec in der.items():
        if name in static:
            raise MapError(f"derived sensor {name!r} also has static cells in 'sensors'")
        if not isinstance(spec, dict) or set(spec) - {"neighbours_of", "connectivity"}:
            raise MapError(f"derived sensor {name!r}: expected {{\"neighbours_of\": ACTION, "
                           f"\"connectivity\": 8}}")
        action = spec.get("neighbours_of", "store.target")
        conn = spec.get("connectivity", 8)
        if not isinstance(action, str) or not action.strip():
            raise MapError(f"derived sensor {name!r}: neighbours_of must name an action")
        if conn not in (4, 8) or isinstance(conn, bool):
            raise MapError(f"derived sensor {name!r}: connectivity must be 4 or 8, not {conn!r}")
        derived[str(name)] = DerivedSensor(action.strip(), int(conn))
    return dynamic, derived


def load_map(path: str | Path | None = None, data: dict | None = None) -> GridMap:
    """Read a map file (JSON).  Schema (all keys optional except one of the area keys)::

        {"name": "fire-patrol",
         "cell_size": 50,
         "origin": [lat, lon], "cols": 20, "rows": 12,      # or
         "bbox": [south, west, north, east],                # or
         "polygon": [[lon, lat], ...]  /  a GeoJSON Polygon object,
         "home": [lat, lon]  or  {"cell": "A1"},            # default: centre of the first cell
         "altitude": 60, "arrival_heading": 0,              # compass degrees
         "sensors": {"inP": <cells>, "fire": <cells>},
         "dynamic": {"nemo": {"yes_answers": 2}},           # optional, see below
         "derived": {"adjacent": {"neighbours_of": "store.target", "connectivity": 8}}}

    where ``<cells>`` is a list of cell names / ``[col, row]`` pairs, ``{"rect": [c0, r0, c1,
    r1]}``, ``{"random": 0.1, "seed": 1}``, inline GeoJSON, or ``{"file": "x.geojson"}`` /
    ``"cells.txt"`` relative to the map file.  ``dynamic`` limits a static sensor to
    ``yes_answers`` yes answers per cell per mission (:class:`DynamicSensor`); ``derived`` declares
    a sensor answered from the cells stored by an action (:class:`DerivedSensor`).

    The file is checked against a schema first (:class:`_MapFile`: every field typed and
    ranged, NaN/Infinity rejected, lat in [-90, 90], lon in [-180, 180], the grid origin within
    +-85 deg, at most :data:`MAX_MAP_CELLS` cells, GeoJSON 2-D and closed rings); then a
    sensor geometry (GeoJSON, file, rect) that covers no cell of the map is an error too.
    Raises :class:`MapError` whose lines read ``map.json: $.sensors.fire[2]: message``.
    """
    base = Path(".")
    label = "map"
    if data is None:
        if path is None:
            raise MapError("no map given")
        p = Path(path)
        label = str(path)
        try:
            data = json.loads(p.read_text(encoding="utf-8-sig"))
        except OSError as exc:
            raise MapError(f"cannot read map {path}: {exc.strerror or exc}") from None
        except UnicodeDecodeError as exc:
            raise MapError(f"map {path}: not UTF-8 text (byte {exc.start})") from None
        except (json.JSONDecodeError, RecursionError) as exc:
            why = exc if isinstance(exc, json.JSONDecodeError) else "nested too deeply"
            raise MapError(f"map {path}: invalid JSON: {why}") from None
        except ValueError as exc:  # e.g. an integer of more than 4,300 digits
            raise MapError(f"map {path}: invalid JSON: {exc}") from None
        base = p.parent
    if not isinstance(data, dict):
        raise MapError(f"{label}: $: a map file must be a JSON object")
    try:
        m = _MAP_ADAPTER.validate_python(data)
    except ValidationError as exc:
        raise schema_error(label, exc) from None
    except RecursionError:
        raise MapError(f"{label}: the map is nested too deeply") from None
    kw: dict[str, Any] = dict(name=m.name, altitude=m.altitude,
              arrival_heading=compass_to_math(m.arrival_heading))
    if m.polygon is not None:
        ring = m.polygon.coordinates[0] if isinstance(m.polygon, _GPolygon) else m.polygon
        grid = _checked_grid(label, "polygon", lambda: GridMap.from_polygon(ring, m.cell_size,
                                                                            **kw))
    elif m.bbox is not None:
        grid = _checked_grid(label, "bbox", lambda: GridMap.from_bbox(*m.bbox,
                                                                      cell_size=m.cell_size, **kw))
    elif m.cols is not None and m.rows is not None:
        origin = m.origin if m.origin is not None else (-35.363261, 149.165230)
        grid = GridMap.from_size(m.cols, m.rows, m.cell_size, origin, **kw)
    else:
        raise MapError(f"{label}: $: map needs one of 'polygon', 'bbox' or 'cols'+'rows'")
    _set_home(grid, m.home, label)
    _load_sensors(grid, data, label, base)
    try:
        grid.dynamic, grid.derived = parse_sensor_rules(data, grid.sensors)
    except MapError as exc:
        import re

        found = re.match(r"(dynamic|derived) sensor '([^']*)'", str(exc))
        where = json_path((found[1], found[2])) if found else "$"
        raise MapError(f"{label}: {where}: {exc}") from None
    return grid


def _set_home(grid: GridMap, home: Any, label: str) -> None:
    """The launch point: a cell name, [lat, lon], or the first location's centre."""
    if isinstance(home, _HomeCell):
        try:
            cid = parse_cell_name(grid, home.cell)
        except ValueError:
            raise MapError(f"{label}: $.home.cell: {home.cell!r} is not a cell name such as "
                           "'A1'") from None
        if cid < 0:
            raise MapError(f"{label}: $.home.cell: home cell {home.cell} is outside the map")
        grid.home = grid.centre(cid)
    elif home is not None:
        grid.home = grid.to_enu(home[0], home[1])
    else:
        grid.home = grid.centre(int(grid.cells[0]))


def _load_sensors(grid: GridMap, data: dict, label: str, base: Path) -> None:
    """The map's ``sensors``: cell sets, relative files from ``base``."""
    for name, spec in (data.get("sensors") or {}).items():
        where = f"{label}: {json_path(('sensors', name))}"
        try:
            ids = _cell_spec(grid, spec, base)
        except MapError as exc:
            raise MapError(f"{where}: {exc}") from None
        if len(ids) == 0 and not isinstance(spec, list):
            raise MapError(f"{where}: the geometry covers no cell of the map (check the "
                           "coordinates: GeoJSON is [lon, lat])")
        grid.set_sensor(str(name), ids)


def _checked_grid(label: str, key: str, make) -> GridMap:
    try:
        return make()
    except MapError as exc:
        raise MapError(f"{label}: $.{key}: {exc}") from None
