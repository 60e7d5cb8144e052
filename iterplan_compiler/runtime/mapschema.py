"""The map file's schema (pydantic): every field typed and ranged, GeoJSON 2-D with closed
rings, and error messages with JSON paths (``map.json: $.sensors.fire[2]: ...``).  Split from
:mod:`.grid`; :func:`.mapfile.load_map` validates against it."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from typing import Annotated, Any, Literal, Union

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

from iterplan_compiler.runtime.grid import MAX_MAP_CELLS, MapError

# -- map schema -------------------------------------------------------------------------------
# Every field of a map file is typed and ranged by these pydantic models (NaN and Infinity are
# rejected, GeoJSON geometries must be 2-D); a violation is a MapError naming the JSON path:
# ``map.json: $.sensors.fire[2]: expected a cell name, [col, row] or [lat, lon]``.

#: the local projection divides by cos(latitude): no grid anchored nearer the poles
MAX_ORIGIN_LAT = 85.0

_Lat = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=-90.0, le=90.0)]
_Lon = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=-180.0, le=180.0)]
_Position = tuple[_Lon, _Lat]  # GeoJSON order; exactly 2 numbers (3-D positions rejected)
_LatLon = tuple[_Lat, _Lon]
_Int = Annotated[int, Field(strict=True)]
_Str = Annotated[str, Field(strict=True, max_length=10_000)]


# finite floats in a range (NaN and Infinity rejected)
_Fraction = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0.0, le=1.0)]
_CellSize = Annotated[float, Field(strict=True, allow_inf_nan=False, le=100_000.0, gt=0.0)]
_Altitude = Annotated[float, Field(strict=True, allow_inf_nan=False, le=10_000.0, gt=0.0)]
_Compass = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=-360.0, le=360.0)]


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
    random: _Fraction
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
    cell_size: _CellSize = 50.0
    origin: _LatLon | None = None
    cols: Annotated[int, Field(strict=True, gt=0, le=MAX_MAP_CELLS)] | None = None
    rows: Annotated[int, Field(strict=True, gt=0, le=MAX_MAP_CELLS)] | None = None
    bbox: tuple[_Lat, _Lon, _Lat, _Lon] | None = None  # south, west, north, east
    polygon: _PolygonArea | None = None
    home: _Home | None = None
    altitude: _Altitude = 60.0
    arrival_heading: _Compass = 0.0
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


_MAP_ADAPTER: TypeAdapter[_MapFile] = TypeAdapter(_MapFile)
_GEOJSON_ADAPTER: TypeAdapter[Any] = TypeAdapter(_GeoJSON)


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
        lines.append(f"{label}: {path}: {_message(dict(err))}")
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
