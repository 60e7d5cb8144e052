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

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

EARTH_RADIUS_M = 6_378_137.0  # WGS-84 equatorial radius

#: largest grid (cols x rows) a map may ask for: 4 M cells (100 x 100 km at 50 m), 32 MB of ids
MAX_MAP_CELLS = 4_000_000


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
    cells: np.ndarray = field(default=None)  # type: ignore[assignment,arg-type]
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
