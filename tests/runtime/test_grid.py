"""Grid maps, ENU <-> lat/lon, cell sets from files."""

import json
import math

import numpy as np
import pytest

from iterplan_compiler.runtime.grid import (
    GridMap,
    LocalFrame,
    MapError,
    compass_to_math,
    math_to_compass,
)
from iterplan_compiler.runtime.mapfile import (
    cells_from_geojson,
    cells_from_text,
    load_map,
    parse_cell_name,
)


def test_enu_roundtrip_and_scale():
    f = LocalFrame(-35.0, 149.0)
    x, y = f.to_enu(-35.0 + 0.001, 149.0 + 0.001)
    assert abs(y - 111.32) < 0.1                     # 0.001 deg latitude ~ 111 m
    assert abs(x - 111.32 * math.cos(math.radians(35))) < 0.1
    lat, lon = f.to_latlon(x, y)
    assert abs(lat + 34.999) < 1e-9 and abs(lon - 149.001) < 1e-9


def test_compass_conversion():
    assert abs(compass_to_math(0) - math.pi / 2) < 1e-12
    assert abs(compass_to_math(90)) < 1e-12
    assert math_to_compass(math.pi) == 270.0


def test_cells_and_names():
    g = GridMap.from_size(30, 4)
    assert g.num_cells == 120 and len(g.cells) == 120
    assert g.cell_name(0) == "A1" and g.cell_name(29) == "AD1" and g.cell_name(30) == "A2"
    for c in (0, 29, 31, 119):
        assert parse_cell_name(g, g.cell_name(c)) == c
    assert g.cell_at(*g.centre(77)) == 77
    assert g.cell_at(-1, 10) == -1


def test_polygon_map_and_geojson_cells(tmp_path):
    # A right triangle: about half of its bounding box's cells are locations.
    f = LocalFrame(-35.0, 149.0)
    pts = [(0, 0), (1000, 0), (0, 1000)]
    ring = [list(reversed(f.to_latlon(x, y))) for x, y in pts]
    g = GridMap.from_polygon(ring + [ring[0]], 50.0)
    assert 180 <= len(g.cells) <= 230
    xs, ys = g.centres()
    assert (xs + ys <= 1000 + 1e-6).all()
    gj = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "geometry": {"type": "Point",
                                         "coordinates": list(reversed(f.to_latlon(60, 60)))}},
        {"type": "Feature", "geometry": {"type": "Polygon", "coordinates": [[
            list(reversed(f.to_latlon(x, y))) for x, y in
            [(0, 0), (100, 0), (100, 100), (0, 100), (0, 0)]]]}}]}
    cells = cells_from_geojson(g, gj)
    assert sorted(g.cell_name(c) for c in cells) == ["A1", "A2", "B1", "B2"]


def test_text_cells():
    g = GridMap.from_size(10, 10)
    lat, lon = g.to_latlon(*g.centre(55))
    ids = cells_from_text(g, f"# comment\nC5\n3,4\n{lat:.7f},{lon:.7f}\n")
    assert ids.tolist() == sorted({parse_cell_name(g, "C5"), 43, 55})
    with pytest.raises(MapError, match="line 1"):
        cells_from_text(g, "Z99\n")


def test_load_map_file(tmp_path):
    (tmp_path / "fire.txt").write_text("B2\nC3\n")
    (tmp_path / "m.json").write_text(json.dumps({
        "name": "t", "cols": 8, "rows": 6, "cell_size": 40, "home": {"cell": "A1"},
        "arrival_heading": 90,
        "sensors": {"inP": {"rect": [1, 1, 3, 2]}, "fire": "fire.txt"}}))
    g = load_map(tmp_path / "m.json")
    assert g.cell_size == 40 and g.home == (20.0, 20.0)
    assert abs(g.arrival_heading) < 1e-12
    assert len(g.sensors["inP"]) == 6
    assert [g.cell_name(c) for c in g.sensors["fire"]] == ["B2", "C3"]


@pytest.mark.parametrize("data,msg", [
    ({}, "needs one of"), ({"cols": 0, "rows": 3}, "positive"),
    ({"cols": 3, "rows": 3, "sensors": {"x": {"file": "nope.txt"}}}, "cannot read"),
    ({"cols": 3, "rows": 3, "home": {"cell": "Q9"}}, "outside"),
])
def test_map_errors(data, msg):
    with pytest.raises(MapError, match=msg):
        load_map(data=data)


def test_million_cells_map_is_cheap():
    g = GridMap.from_size(1000, 1000)
    xs, ys = g.centres()
    assert len(xs) == 1_000_000 and xs.dtype == np.float64
    ring = np.array([[0, 0], [50000, 0], [0, 50000]], dtype=float)
    assert len(g.cells_in_polygon(ring)) > 400_000
