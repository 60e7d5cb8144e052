"""Grid maps: the discretisation the Iterator walks over.

A :class:`GridMap` is a regular grid of square cells (default 50 m, as in the paper) laid over a
local East-North-Up (ENU) tangent plane anchored at ``origin`` (lat, lon).  Cells are numbered
``id = row * cols + col`` with row 0 at the southern edge and col 0 at the western edge.  Only the
cells whose centre lies inside the mission area are *locations*; they are kept as a sorted NumPy
``int64`` array so a map of millions of cells needs no per-cell Python objects.

Coordinates: ``x`` = metres east, ``y`` = metres north of the origin.  Angles used by the runtime
are mathematical (radians, counter-clockwise from east); map files speak compass degrees
(clockwise from north) and are converted at the boundary (:func:`compass_to_math`).

The lat/lon conversion is a local equirectangular projection about the origin (error < 0.1 % over
a few tens of kilometres), which is all a 50 m grid needs.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any, Literal, Union

import numpy as np
from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Discriminator,
    Field,
    Tag,
    TypeAdapter,
    ValidationError,
    model_validator,
)

EARTH_RADIUS_M = 6_378_137.0  # WGS-84 equatorial radius


def compass_to_math(deg: float) -> float:
    """Compass degrees (0 = north, clockwise) -> math radians (0 = east, counter-clockwise)."""
    return math.radians(90.0 - deg)


def math_to_compass(rad: float) -> float:
    """Math radians -> compass degrees in [0, 360)."""
    return (90.0 - math.degrees(rad)) % 360.0


class MapError(ValueError):
    """A map or cell-set file is malformed; the message is meant for the user."""


@dataclass(frozen=True)
class LocalFrame:
    """Local ENU tangent plane at ``(lat0, lon0)``."""

    lat0: float
    lon0: float

    def to_enu(self, lat, lon):
        """(lat, lon) degrees -> (x east, y north) metres; works on scalars and arrays."""
        k = math.pi / 180.0 * EARTH_RADIUS_M
        x = (np.asarray(lon, dtype=np.float64) - self.lon0) * k * math.cos(math.radians(self.lat0))
        y = (np.asarray(lat, dtype=np.float64) - self.lat0) * k
        if np.ndim(x) == 0:
            return float(x), float(y)
        return x, y

    def to_latlon(self, x, y):
        """(x east, y north) metres -> (lat, lon) degrees; scalars and arrays."""
        k = math.pi / 180.0 * EARTH_RADIUS_M
        lat = self.lat0 + np.asarray(y, dtype=np.float64) / k
        lon = self.lon0 + np.asarray(x, dtype=np.float64) / (k * math.cos(math.radians(self.lat0)))
        if np.ndim(lat) == 0:
            return float(lat), float(lon)
        return lat, lon


def points_in_polygon(px: np.ndarray, py: np.ndarray, ring: np.ndarray) -> np.ndarray:
    """Even-odd ray casting of many points against one closed ring (``(k, 2)`` array).

    Vectorised over the points, looping over the (few) polygon edges.
    """
    inside = np.zeros(px.shape, dtype=bool)
    n = len(ring)
    for i in range(n):
        x1, y1 = ring[i]
        x2, y2 = ring[(i + 1) % n]
        if y1 == y2:
            continue  # horizontal edges never cross a horizontal ray
        crosses = (y1 > py) != (y2 > py)
        xint = x1 + (py - y1) * (x2 - x1) / (y2 - y1)
        inside ^= crosses & (px < xint)
    return inside


@dataclass(frozen=True)
class DynamicSensor:
    """A sensor whose *yes* answers run out: at each of its cells it answers yes at most
    ``yes_answers`` times, then no for ever (the observed thing "leaves" -- Find Nemo)."""

    yes_answers: int = 1


@dataclass(frozen=True)
class DerivedSensor:
    """A sensor computed at run time from a shared set of cells: every execution of the
    controllable action ``neighbours_of`` (e.g. ``store.target``) adds the current cell to the
    set; the sensor answers yes for a cell equal or adjacent (``connectivity`` 4 or 8) to a
    stored cell (Search and Map)."""

    neighbours_of: str = "store.target"
    connectivity: int = 8


@dataclass
class GridMap:
    """A grid of ``cols x rows`` cells of ``cell_size`` metres; ``cells`` are the locations.

    ``frame`` anchors the grid's south-west corner at ENU (0, 0).  ``home`` is the launch point in
    ENU metres.  ``sensors`` maps a sensor name (``inP``, ``fire``...) to a sorted array of cell
    ids where that sensor answers *yes*.
    """

    frame: LocalFrame
    cols: int
    rows: int
    cell_size: float = 50.0
    cells: np.ndarray = field(default=None)  # type: ignore[assignment]
    home: tuple[float, float] = (0.0, 0.0)
    altitude: float = 60.0
    arrival_heading: float = math.pi / 2  # math radians; default: arrive flying north
    sensors: dict[str, np.ndarray] = field(default_factory=dict)
    name: str = "map"
    #: sensor name -> :class:`DynamicSensor` (map key ``"dynamic"``); the static cells stay in
    #: :attr:`sensors`, the runtime bindings (:func:`~iterplan_compiler.runtime.bindings.
    #: map_rule_bindings`) count the answers per mission.
    dynamic: dict[str, DynamicSensor] = field(default_factory=dict)
    #: sensor name -> :class:`DerivedSensor` (map key ``"derived"``); no static cells.
    derived: dict[str, DerivedSensor] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.cols <= 0 or self.rows <= 0 or self.cell_size <= 0:
            raise MapError("grid needs positive cols, rows and cell_size")
        if self.cols * self.rows > MAX_MAP_CELLS:
            raise MapError(f"a {self.cols} x {self.rows} grid has {self.cols * self.rows:,} "
                           f"cells; at most {MAX_MAP_CELLS:,} (use a larger cell_size)")
        if self.cells is None:
            self.cells = np.arange(self.cols * self.rows, dtype=np.int64)
        else:
            self.cells = np.unique(np.asarray(self.cells, dtype=np.int64))

    # -- geometry ---------------------------------------------------------------------------
    @property
    def num_cells(self) -> int:
        return int(self.cols * self.rows)

    def centres(self, ids: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """ENU centres (float64) of ``ids`` (default: all locations)."""
        ids = self.cells if ids is None else np.asarray(ids, dtype=np.int64)
        col = ids % self.cols
        row = ids // self.cols
        return (col + 0.5) * self.cell_size, (row + 0.5) * self.cell_size

    def centre(self, cell: int) -> tuple[float, float]:
        col, row = int(cell) % self.cols, int(cell) // self.cols
        return (col + 0.5) * self.cell_size, (row + 0.5) * self.cell_size

    def centre_point(self) -> tuple[float, float]:
        """Centre of the locations' bounding box (where a finished mission loiters)."""
        xs, ys = self.centres()
        if len(xs) == 0:
            return self.cols * self.cell_size / 2, self.rows * self.cell_size / 2
        return float(xs.min() + xs.max()) / 2, float(ys.min() + ys.max()) / 2

    def cell_at(self, x, y):
        """Cell id containing ENU point(s), or -1 outside the grid rectangle."""
        col = np.floor(np.asarray(x, dtype=np.float64) / self.cell_size).astype(np.int64)
        row = np.floor(np.asarray(y, dtype=np.float64) / self.cell_size).astype(np.int64)
        ok = (col >= 0) & (col < self.cols) & (row >= 0) & (row < self.rows)
        ids = np.where(ok, row * self.cols + col, -1)
        return int(ids) if ids.ndim == 0 else ids

    def cell_name(self, cell: int) -> str:
        """Human name like the paper's ``C5``: column letters, row number (1-based)."""
        col, row = int(cell) % self.cols, int(cell) // self.cols
        letters = ""
        col += 1
        while col:
            col, rem = divmod(col - 1, 26)
            letters = chr(65 + rem) + letters
        return f"{letters}{row + 1}"

    def cells_in_polygon(self, ring_xy: np.ndarray) -> np.ndarray:
        """Cell ids (of the whole grid) whose centre lies inside the ENU ring."""
        ring_xy = np.asarray(ring_xy, dtype=np.float64)
        x0, y0 = ring_xy.min(axis=0)
        x1, y1 = ring_xy.max(axis=0)
        # Restrict the test to the bounding box of the polygon: cheap and keeps 10^6-cell maps fast.
        c0 = max(int(x0 // self.cell_size), 0)
        c1 = min(int(x1 // self.cell_size) + 1, self.cols)
        r0 = max(int(y0 // self.cell_size), 0)
        r1 = min(int(y1 // self.cell_size) + 1, self.rows)
        if c0 >= c1 or r0 >= r1:
            return np.zeros(0, dtype=np.int64)
        cc, rr = np.meshgrid(np.arange(c0, c1), np.arange(r0, r1))
        ids = (rr * self.cols + cc).ravel().astype(np.int64)
        px, py = (cc.ravel() + 0.5) * self.cell_size, (rr.ravel() + 0.5) * self.cell_size
        return np.sort(ids[points_in_polygon(px, py, ring_xy)])

    def to_latlon(self, x, y):
        return self.frame.to_latlon(x, y)

    def to_enu(self, lat, lon):
        return self.frame.to_enu(lat, lon)

    # -- constructors -----------------------------------------------------------------------
    @classmethod
    def from_size(cls, cols: int, rows: int, cell_size: float = 50.0,
                  origin: tuple[float, float] = (-35.363261, 149.165230), **kw) -> GridMap:
        """A rectangular ``cols x rows`` grid whose south-west corner is at ``origin``."""
        return cls(LocalFrame(*origin), cols, rows, cell_size, **kw)

    @classmethod
    def from_bbox(cls, south: float, west: float, north: float, east: float,
                  cell_size: float = 50.0, **kw) -> GridMap:
        """Cover a lat/lon bounding box with whole cells (rounding up)."""
        if not (north > south and east > west):
            raise MapError("bbox must satisfy south < north and west < east")
        frame = LocalFrame(south, west)
        w, h = frame.to_enu(north, east)
        return cls(frame, max(1, math.ceil(w / cell_size)), max(1, math.ceil(h / cell_size)),
                   cell_size, **kw)

    @classmethod
    def from_polygon(cls, ring_latlon: Sequence[Sequence[float]], cell_size: float = 50.0,
                     **kw) -> GridMap:
        """Grid over a polygon given as GeoJSON-order ``[lon, lat]`` vertices; cells outside the
        polygon are not locations."""
        ring = np.asarray(ring_latlon, dtype=np.float64)
        if ring.ndim != 2 or ring.shape[1] < 2 or len(ring) < 3:
            raise MapError("polygon needs at least 3 [lon, lat] vertices")
        south, west = ring[:, 1].min(), ring[:, 0].min()
        north, east = ring[:, 1].max(), ring[:, 0].max()
        grid = cls.from_bbox(south, west, north, east, cell_size, **kw)
        x, y = grid.frame.to_enu(ring[:, 1], ring[:, 0])
        grid.cells = grid.cells_in_polygon(np.column_stack([x, y]))
        if len(grid.cells) == 0:
            raise MapError("polygon contains no cell centre; use a smaller cell_size")
        return grid

    # -- sensors ----------------------------------------------------------------------------
    def set_sensor(self, name: str, ids: Iterable[int]) -> None:
        """Declare the cells where sensor ``name`` answers yes (ids outside the map are dropped)."""
        arr = np.unique(np.asarray(list(ids) if not isinstance(ids, np.ndarray) else ids,
                                   dtype=np.int64))
        self.sensors[name] = arr[(arr >= 0) & (arr < self.num_cells)]

    def sensor_mask(self, name: str) -> np.ndarray:
        """Boolean array over all grid cells for sensor ``name`` (False if unknown)."""
        mask = np.zeros(self.num_cells, dtype=bool)
        if name in self.sensors:
            mask[self.sensors[name]] = True
        return mask


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


# -- map schema -------------------------------------------------------------------------------
# Every field of a map file is typed and ranged by these pydantic models (NaN and Infinity are
# rejected, GeoJSON geometries must be 2-D); a violation is a MapError naming the JSON path:
# ``map.json: $.sensors.fire[2]: expected a cell name, [col, row] or [lat, lon]``.

#: largest grid (cols x rows) a map may ask for: 4 M cells (100 x 100 km at 50 m), 32 MB of ids
MAX_MAP_CELLS = 4_000_000
#: the local projection divides by cos(latitude): no grid anchored nearer the poles
MAX_ORIGIN_LAT = 85.0

_Lat = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=-90.0, le=90.0)]
_Lon = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=-180.0, le=180.0)]
_Position = tuple[_Lon, _Lat]  # GeoJSON order; exactly 2 numbers (3-D positions rejected)
_LatLon = tuple[_Lat, _Lon]
_Int = Annotated[int, Field(strict=True)]
_Str = Annotated[str, Field(strict=True, max_length=10_000)]


def _finite(lo: float | None = None, hi: float | None = None, *, gt: float | None = None):
    return Annotated[float, Field(strict=True, allow_inf_nan=False, ge=lo, le=hi, gt=gt)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class _GeoBase(BaseModel):
    # RFC 7946 allows foreign members ("bbox", "id", ...): ignored, never used
    model_config = ConfigDict(extra="ignore", frozen=True)


def _ring(v: list) -> list:
    if len(v) < 4:
        raise ValueError(f"a polygon ring needs at least 4 positions (closed), not {len(v)}")
    if tuple(v[0]) != tuple(v[-1]):
        raise ValueError("a polygon ring must be closed (its last position equal to the first)")
    return v


_Ring = Annotated[list[_Position], AfterValidator(_ring)]


class _GPoint(_GeoBase):
    type: Literal["Point"]
    coordinates: _Position


class _GMultiPoint(_GeoBase):
    type: Literal["MultiPoint"]
    coordinates: list[_Position]


class _GPolygon(_GeoBase):
    type: Literal["Polygon"]
    coordinates: Annotated[list[_Ring], Field(min_length=1)]


class _GMultiPolygon(_GeoBase):
    type: Literal["MultiPolygon"]
    coordinates: list[Annotated[list[_Ring], Field(min_length=1)]]


class _GGeometryCollection(_GeoBase):
    type: Literal["GeometryCollection"]
    geometries: list[_Geometry]


_Geometry = Annotated[Union[_GPoint, _GMultiPoint, _GPolygon, _GMultiPolygon,  # noqa: UP007
                            _GGeometryCollection], Field(discriminator="type")]


class _GFeature(_GeoBase):
    type: Literal["Feature"]
    geometry: _Geometry | None = None
    properties: dict[str, Any] | None = None


class _GFeatureCollection(_GeoBase):
    type: Literal["FeatureCollection"]
    features: list[_GFeature]


_GeoJSON = Annotated[Union[_GPoint, _GMultiPoint, _GPolygon, _GMultiPolygon,  # noqa: UP007
                           _GGeometryCollection, _GFeature, _GFeatureCollection],
                     Field(discriminator="type")]


def _cell_entry(v: Any) -> Any:
    """One entry of a cell list: a cell name / ``"lat,lon"`` text, ``[col, row]`` (integers
    >= 0) or ``[lat, lon]`` (finite degrees)."""
    if isinstance(v, str):
        if not v.strip() or len(v) > 100:
            raise ValueError(f"expected a cell name such as 'C5', got {v[:40]!r}")
        return v
    if isinstance(v, list | tuple) and len(v) == 2 and not any(isinstance(x, bool) for x in v):
        a, b = v
        if isinstance(a, int) and isinstance(b, int):
            if a < 0 or b < 0:
                raise ValueError(f"[col, row] must be integers >= 0, got {list(v)}")
            return [a, b]
        if all(isinstance(x, int | float) for x in v):
            if not all(math.isfinite(x) for x in v):
                raise ValueError(f"[lat, lon] must be finite numbers, got {list(v)}")
            if not (-90 <= a <= 90 and -180 <= b <= 180):
                raise ValueError(f"[lat, lon] must be within [-90, 90] x [-180, 180], "
                                 f"got {list(v)}")
            return [float(a), float(b)]
    raise ValueError(f"expected a cell name, [col, row] or [lat, lon], got {_short(v)}")


def _short(v: Any) -> str:
    text = json.dumps(v, allow_nan=True, default=str)
    return text if len(text) <= 60 else text[:57] + "..."


class _Rect(_Strict):
    rect: tuple[Annotated[int, Field(strict=True, ge=0)], Annotated[int, Field(strict=True, ge=0)],
                Annotated[int, Field(strict=True, ge=0)], Annotated[int, Field(strict=True, ge=0)]]

    @model_validator(mode="after")
    def _ordered(self) -> _Rect:
        c0, r0, c1, r1 = self.rect
        if c1 < c0 or r1 < r0:
            raise ValueError(f"rect [c0, r0, c1, r1] needs c0 <= c1 and r0 <= r1, got "
                             f"{list(self.rect)}")
        return self


class _Random(_Strict):
    random: _finite(0.0, 1.0)
    seed: Annotated[int, Field(strict=True, ge=0, le=2**63 - 1)] = 0


class _File(_Strict):
    file: Annotated[str, Field(strict=True, min_length=1, max_length=4096)]


class _Cells(_Strict):
    cells: _CellSet


def _cellset_kind(v: Any) -> str | None:
    if isinstance(v, list):
        return "<list>"
    if isinstance(v, str):
        return "<name>"
    if isinstance(v, dict):
        if "type" in v:
            return "<geojson>"
        for k in ("cells", "rect", "random", "file"):
            if k in v:
                return f"<{k}>"
    return None


_CellSet = Annotated[
    Union[  # noqa: UP007
        Annotated[list[Annotated[Any, BeforeValidator(_cell_entry)]], Tag("<list>")],
        Annotated[Annotated[str, Field(strict=True, min_length=1, max_length=4096)],
                  Tag("<name>")],
        Annotated[_GeoJSON, Tag("<geojson>")],
        Annotated[_Cells, Tag("<cells>")],
        Annotated[_Rect, Tag("<rect>")],
        Annotated[_Random, Tag("<random>")],
        Annotated[_File, Tag("<file>")],
    ],
    Discriminator(_cellset_kind, custom_error_type="cell_set",
                  custom_error_message="expected a cell set: a list of cells, a file name, "
                  "{\"rect\": [c0, r0, c1, r1]}, {\"random\": p, \"seed\": n}, "
                  "{\"file\": NAME}, {\"cells\": ...} or a GeoJSON object"),
]
_Cells.model_rebuild()
_GGeometryCollection.model_rebuild()


class _HomeCell(_Strict):
    cell: Annotated[str, Field(strict=True, min_length=1, max_length=100)]


def _kind(list_tag: str, dict_tag: str):
    def kind(v: Any) -> str | None:
        return list_tag if isinstance(v, list | tuple) else dict_tag if isinstance(v, dict) \
            else None
    return kind


_Home = Annotated[
    Union[Annotated[_LatLon, Tag("<latlon>")], Annotated[_HomeCell, Tag("<cell>")]],  # noqa: UP007
    Discriminator(_kind("<latlon>", "<cell>"), custom_error_type="home",
                  custom_error_message="expected [lat, lon] or {\"cell\": NAME}")]
_PolygonArea = Annotated[
    Union[Annotated[Annotated[list[_Position], Field(min_length=3)], Tag("<ring>")],  # noqa: UP007
          Annotated[_GPolygon, Tag("<polygon>")]],
    Discriminator(_kind("<ring>", "<polygon>"), custom_error_type="polygon",
                  custom_error_message="expected a list of [lon, lat] vertices or a GeoJSON "
                  "Polygon")]


class _MapFile(_Strict):
    name: Annotated[str, Field(strict=True, max_length=200)] = "map"
    description: _Str | None = None
    cell_size: _finite(hi=100_000.0, gt=0.0) = 50.0
    origin: _LatLon | None = None
    cols: Annotated[int, Field(strict=True, gt=0, le=MAX_MAP_CELLS)] | None = None
    rows: Annotated[int, Field(strict=True, gt=0, le=MAX_MAP_CELLS)] | None = None
    bbox: tuple[_Lat, _Lon, _Lat, _Lon] | None = None  # south, west, north, east
    polygon: _PolygonArea | None = None
    home: _Home | None = None
    altitude: _finite(hi=10_000.0, gt=0.0) = 60.0
    arrival_heading: _finite(-360.0, 360.0) = 0.0
    sensors: dict[Annotated[str, Field(strict=True, min_length=1, max_length=200)],
                  _CellSet] | None = None
    # the sensor rules' semantics (and messages) are parse_sensor_rules'; typed here as objects
    dynamic: dict[str, Any] | list | None = None
    derived: dict[str, Any] | list | None = None

    @model_validator(mode="after")
    def _area(self) -> _MapFile:
        if self.origin is not None and abs(self.origin[0]) > MAX_ORIGIN_LAT:
            raise _PathError(("origin", 0), f"latitude {self.origin[0]} is too near a pole: the "
                             f"grid's local projection needs |lat| <= {MAX_ORIGIN_LAT:g}")
        if self.bbox is not None:
            s, w, n, e = self.bbox
            if not (n > s and e > w):
                raise _PathError(("bbox",), "bbox [south, west, north, east] must satisfy "
                                 "south < north and west < east")
            if max(abs(s), abs(n)) > MAX_ORIGIN_LAT:
                raise _PathError(("bbox",), f"latitudes must be within +-{MAX_ORIGIN_LAT:g} "
                                 "(the grid's local projection degenerates at the poles)")
        if (self.cols is None) != (self.rows is None):
            raise _PathError((), "'cols' and 'rows' go together")
        if self.cols is not None and self.rows is not None and \
                self.cols * self.rows > MAX_MAP_CELLS:
            raise _PathError(("cols",), f"a {self.cols} x {self.rows} grid has "
                             f"{self.cols * self.rows:,} cells; at most {MAX_MAP_CELLS:,}")
        return self


class _PathError(ValueError):
    """A semantic schema error at a known path (raised from a model validator)."""

    def __init__(self, loc: tuple, message: str) -> None:
        super().__init__(message)
        self.loc = loc
        self.message = message


_MAP_ADAPTER = TypeAdapter(_MapFile)
_GEOJSON_ADAPTER = TypeAdapter(_GeoJSON)


def json_path(loc: Sequence[Any]) -> str:
    """``("sensors", "fire", 2)`` -> ``$.sensors.fire[2]`` (tags of unions left out)."""
    out = "$"
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif isinstance(part, str) and (part.startswith("<") and part.endswith(">")
                                        or part in _GEOJSON_TYPES):
            continue  # a tag of a union (cell set, home, polygon, GeoJSON type)
        elif isinstance(part, str) and part.replace("_", "a").isalnum() and \
                not part[:1].isdigit():
            out += f".{part}"
        else:
            out += "[" + json.dumps(str(part)) + "]"
    return out


_GEOJSON_TYPES = frozenset({"Point", "MultiPoint", "Polygon", "MultiPolygon",
                            "GeometryCollection", "Feature", "FeatureCollection"})


def _message(err: dict) -> str:
    typ, ctx = err.get("type", ""), err.get("ctx") or {}
    msg = str(err.get("msg", "invalid value"))
    if typ == "value_error":
        exc = ctx.get("error")
        if isinstance(exc, _PathError):
            return exc.message
        msg = msg.removeprefix("Value error, ")
    elif typ == "greater_than" and ctx.get("gt") == 0:
        msg = f"must be positive, got {_short(err.get('input'))}"
    elif typ == "too_long" and ctx.get("max_length") == 2 and ctx.get("field_type") == "Tuple":
        msg = (f"a position is 2 numbers ([lon, lat] in GeoJSON, [lat, lon] elsewhere), not "
               f"{ctx.get('actual_length')}: 3-D positions are not supported")
    elif typ == "finite_number":
        msg = f"must be a finite number, got {_short(err.get('input'))}"
    elif typ == "extra_forbidden":
        msg = "unknown key"
    elif typ in ("float_type", "int_type", "string_type", "dict_type", "list_type",
                 "tuple_type", "model_type", "model_attributes_type"):
        msg = f"{msg.rstrip('.')}, got {_short(err.get('input'))}"
    return msg


def schema_error(label: str, exc: ValidationError) -> MapError:
    """A :class:`MapError` for the first violations (at most 3) of a schema, with JSON paths."""
    lines = []
    seen = set()
    for err in exc.errors(include_url=False):
        loc = tuple(err.get("loc", ()))
        ctx_err = (err.get("ctx") or {}).get("error")
        if isinstance(ctx_err, _PathError):
            loc = loc + tuple(ctx_err.loc)
        path = json_path(loc)
        if path in seen:
            continue
        seen.add(path)
        lines.append(f"{label}: {path}: {_message(err)}")
        if len(lines) == 3:
            break
    extra = exc.error_count() - len(lines)
    if extra > 0:
        lines[-1] += f" (and {extra} more problem(s))"
    return MapError("\n".join(lines))


def validate_geojson(obj: Any, label: str) -> None:
    """:class:`MapError` (with JSON paths) unless ``obj`` is 2-D GeoJSON we can use."""
    try:
        _GEOJSON_ADAPTER.validate_python(obj)
    except ValidationError as exc:
        raise schema_error(label, exc) from None


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
    kw = dict(name=m.name, altitude=m.altitude,
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
    if isinstance(m.home, _HomeCell):
        try:
            cid = parse_cell_name(grid, m.home.cell)
        except ValueError:
            raise MapError(f"{label}: $.home.cell: {m.home.cell!r} is not a cell name such as "
                           "'A1'") from None
        if cid < 0:
            raise MapError(f"{label}: $.home.cell: home cell {m.home.cell} is outside the map")
        grid.home = grid.centre(cid)
    elif m.home is not None:
        grid.home = grid.to_enu(m.home[0], m.home[1])
    else:
        grid.home = grid.centre(int(grid.cells[0]))
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
    try:
        grid.dynamic, grid.derived = parse_sensor_rules(data, grid.sensors)
    except MapError as exc:
        import re

        m = re.match(r"(dynamic|derived) sensor '([^']*)'", str(exc))
        where = json_path((m[1], m[2])) if m else "$"
        raise MapError(f"{label}: {where}: {exc}") from None
    return grid


def _checked_grid(label: str, key: str, make) -> GridMap:
    try:
        return make()
    except MapError as exc:
        raise MapError(f"{label}: $.{key}: {exc}") from None
