"""Bad maps (issue 14, "127 bad maps"): every class is a MapError naming the JSON path, and
``iterc run`` exits 1 on it (never 3), before flying anything."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import pytest

from iterplan_compiler import cli
from iterplan_compiler.runtime.grid import MAX_MAP_CELLS, MapError
from iterplan_compiler.runtime.mapfile import load_map
from iterplan_compiler.runtime.mapschema import json_path

REPO = Path(__file__).resolve().parents[2]
BASE = json.loads((REPO / "examples" / "fire_patrol.json").read_text())
POLY = {"type": "Polygon", "coordinates": [[[149.1653, -35.3632], [149.1660, -35.3632],
                                            [149.1660, -35.3628], [149.1653, -35.3632]]]}


def with_(**changes):
    return {**BASE, **changes}


# (class of bad input, map data, JSON path the message must name, words it must contain)
BAD = [
    ("string for a number", with_(cell_size="50"), "$.cell_size", "valid number"),
    ("string for an integer", with_(cols="8"), "$.cols", "valid integer"),
    ("bool for an integer", with_(rows=True), "$.rows", "valid integer"),
    ("NaN origin", with_(origin=[math.nan, 149.0]), "$.origin[0]", "finite"),
    ("Infinity altitude", with_(altitude=math.inf), "$.altitude", "finite"),
    ("-Infinity heading", with_(arrival_heading=-math.inf), "$.arrival_heading", "finite"),
    ("origin at the pole", with_(origin=[90, 0]), "$.origin[0]", "pole"),
    ("latitude out of range", with_(home=[100, 0]), "$.home[0]", "90"),
    ("longitude out of range", with_(origin=[0, 200]), "$.origin[1]", "180"),
    ("3-D GeoJSON point", with_(sensors={"fire": {"type": "Point",
                                                   "coordinates": [149.1653, -35.3632, 10]}}),
     "$.sensors.fire.coordinates", "3-D"),
    ("3-D polygon vertex", with_(sensors={"fire": {"type": "Polygon", "coordinates": [[
        [149.1653, -35.3632, 1], [149.166, -35.3632], [149.166, -35.3628],
        [149.1653, -35.3632]]]}}), "$.sensors.fire.coordinates[0][0]", "3-D"),
    ("open polygon ring", with_(sensors={"fire": {"type": "Polygon", "coordinates": [[
        [149.1653, -35.3632], [149.166, -35.3632], [149.166, -35.3628],
        [149.1653, -35.3630]]]}}), "$.sensors.fire.coordinates[0]", "closed"),
    ("unsupported geometry", with_(sensors={"fire": {"type": "LineString",
                                                      "coordinates": [[0, 0], [1, 1]]}}),
     "$.sensors.fire", "LineString"),
    ("geometry covering no cell", with_(sensors={"fire": {"type": "Polygon", "coordinates": [[
        [0, 0], [0, 1], [1, 1], [0, 0]]]}}), "$.sensors.fire", "covers no cell"),
    ("huge grid", with_(cols=100_000, rows=100_000), "$.cols", f"{MAX_MAP_CELLS:,}"),
    ("huge bbox", {"bbox": [-40, 100, 40, 170], "cell_size": 1}, "$.bbox", "cells"),
    ("bad cell entry", with_(sensors={"fire": ["B2", "G7", {"x": 1}]}), "$.sensors.fire[2]",
     "cell name"),
    ("cell outside the map", with_(sensors={"fire": ["B2", "Z99"]}), "$.sensors.fire",
     "outside"),
    ("rect outside the map", with_(sensors={"fire": {"rect": [0, 0, 100, 2]}}),
     "$.sensors.fire", "outside"),
    ("not a cell set", with_(sensors={"fire": 5}), "$.sensors.fire", "cell set"),
    ("random fraction out of range", with_(sensors={"fire": {"random": 2}}),
     "$.sensors.fire.random", "1"),
    ("unknown key", with_(colz=3), "$.colz", "unknown key"),
    ("home cell outside", with_(home={"cell": "Q99"}), "$.home.cell", "outside"),
    ("home of the wrong shape", with_(home=3), "$.home", "[lat, lon]"),
    ("negative cell size", with_(cell_size=-5), "$.cell_size", "positive"),
    ("bad dynamic rule", with_(dynamic={"fire": {"yes_answers": 0}}), "$.dynamic.fire",
     "yes_answers"),
    ("not an object", [1, 2], "$", "JSON object"),
    ("no area", {"name": "x"}, "$", "needs one of"),
]


@pytest.mark.parametrize("what,data,path,words", BAD, ids=[b[0] for b in BAD])
def test_bad_map_is_a_map_error_with_its_json_path(what, data, path, words):
    with pytest.raises(MapError) as exc:
        load_map(data=data)
    msg = str(exc.value)
    assert f"map: {path}: " in msg, msg
    assert words in msg, msg


@pytest.fixture(scope="module")
def controller(tmp_path_factory) -> Path:
    ctl = tmp_path_factory.mktemp("ctl") / "fire_patrol.py"
    shutil.copy(REPO / "tests" / "runtime" / "fire_patrol.py", ctl)
    return ctl


def _write(tmp_path: Path, data) -> Path:
    # allow_nan: what a careless tool writes; json.loads reads NaN/Infinity back as floats
    p = tmp_path / "map.json"
    p.write_text(json.dumps(data, allow_nan=True))
    return p


@pytest.mark.parametrize("what,data,path,words", BAD, ids=[b[0] for b in BAD])
def test_iterc_run_exits_1_on_a_bad_map(what, data, path, words, tmp_path, controller, capsys):
    m = _write(tmp_path, data)
    out = tmp_path / "out"
    rc = cli.main(["run", str(controller), "--map", str(m), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 1, err
    assert f"{m}: {path}: " in err, err
    assert "Traceback" not in err


@pytest.mark.parametrize("text,words", [
    ('{"cols": 3, "rows": 3, "cell_size": 1' + "0" * 5000 + "}", "invalid JSON"),
    ("[" * 100_000 + "]" * 100_000, "JSON"),
    ("\xff\xfe", "UTF-8"),
    ('{"cols": 3, "rows": 3, "cell_size": NaN}', "$.cell_size: must be a finite"),
])
def test_unreadable_map_texts(text, words, tmp_path):
    p = tmp_path / "m.json"
    p.write_bytes(text.encode("latin-1") if text.startswith("\xff") else text.encode())
    with pytest.raises(MapError) as exc:
        load_map(p)
    assert words in str(exc.value)


def test_sensor_geojson_file_is_validated(tmp_path):
    (tmp_path / "fire.geojson").write_text(json.dumps(
        {"type": "FeatureCollection", "features": [
            {"type": "Feature", "properties": {}, "geometry": {
                "type": "Point", "coordinates": [149.1653, -35.3632, 3]}}]}))
    (tmp_path / "m.json").write_text(json.dumps(with_(sensors={"fire": "fire.geojson"})))
    with pytest.raises(MapError) as exc:
        load_map(tmp_path / "m.json")
    msg = str(exc.value)
    assert "$.sensors.fire" in msg and "fire.geojson: $.features[0].geometry.coordinates" in msg


def test_good_maps_still_load():
    for name in ("cover", "find_nemo", "fire_patrol", "ordered_patrol", "search_and_map"):
        load_map(REPO / "examples" / f"{name}.json")
    g = load_map(data={"polygon": POLY, "cell_size": 10})
    assert len(g.cells) > 0


def test_json_path_format():
    assert json_path(("sensors", "fire", 2)) == "$.sensors.fire[2]"
    assert json_path(("sensors", "p.0", "<list>", 1)) == '$.sensors["p.0"][1]'
    assert json_path(()) == "$"
