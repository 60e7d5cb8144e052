"""`iterc run` end to end on the built-in simulator."""

import json
import shutil
from pathlib import Path

from iterplan_compiler.cli import main

HERE = Path(__file__).parent


def setup_files(tmp_path):
    ctl = tmp_path / "fire_patrol_ctl.py"
    shutil.copy(HERE / "fire_patrol.py", ctl)
    m = tmp_path / "map.json"
    (tmp_path / "fire.txt").write_text("C3\nE5\n")
    m.write_text(json.dumps({"name": "cli", "cols": 8, "rows": 6, "home": {"cell": "A1"},
                             "sensors": {"inP": ["B2", "C3", "E5", "G6", "H1"],
                                         "fire": "fire.txt"}}))
    return ctl, m


def test_run_writes_outputs(tmp_path, capsys):
    ctl, m = setup_files(tmp_path)
    out = tmp_path / "out"
    rc = main(["run", str(ctl), "--map", str(m), "--out", str(out), "--ideal-compute",
               "--seed", "2"])
    cap = capsys.readouterr()
    assert rc == 0, cap.err
    assert "mission completed" in cap.out and "visited 5 cells, 2 photos" in cap.out
    assert "visited" in cap.err  # progress lines
    for f in ("track.csv", "track.geojson", "events.csv", "summary.json", "track.png"):
        assert (out / f).stat().st_size > 0
    s = json.loads((out / "summary.json").read_text())
    assert s["arrivals"] == 5 and s["photos"] == 2 and s["ok"]
    # Deterministic outputs with --ideal-compute.
    out2 = tmp_path / "out2"
    assert main(["run", str(ctl), "--map", str(m), "--out", str(out2), "--ideal-compute",
                 "--seed", "2", "--quiet", "--no-plot"]) == 0
    for f in ("track.csv", "track.geojson", "events.csv", "summary.json"):
        assert (out / f).read_text() == (out2 / f).read_text()


def test_run_bad_inputs(tmp_path, capsys):
    ctl, m = setup_files(tmp_path)
    assert main(["run", str(tmp_path / "nope.py"), "--map", str(m)]) == 1
    assert "not found" in capsys.readouterr().err
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    assert main(["run", str(ctl), "--map", str(bad)]) == 1
    assert "invalid JSON" in capsys.readouterr().err
    nofire = tmp_path / "nofire.json"
    nofire.write_text(json.dumps({"cols": 3, "rows": 3, "sensors": {"inP": ["A1"]}}))
    assert main(["run", str(ctl), "--map", str(nofire), "--out", str(tmp_path / "o")]) == 1
    assert "sensor 'fire'" in capsys.readouterr().err


def test_run_rejects_broken_controller_modules(tmp_path, capsys):
    """A module that calls sys.exit(0) or whose table points at a missing state is bad
    input (exit 1 with the reason), never a silent exit 0 or a crash mid-mission."""
    ctl, m = setup_files(tmp_path)
    exits = tmp_path / "exits.py"
    exits.write_text("import sys\nsys.exit(0)\n")
    assert main(["run", str(exits), "--map", str(m), "--out", str(tmp_path / "o")]) == 1
    assert "cannot import" in capsys.readouterr().err
    bad = tmp_path / "bad.py"
    bad.write_text("from iterplan_compiler.runtime.controller import ControllerTable\n"
                   "TABLE = ControllerTable('bad', 2, 0, {0: {'has.next': 5}, 1: {}},\n"
                   "    frozenset({'has.next'}), frozenset({'y.next', 'n.next'}))\n")
    assert main(["run", str(bad), "--map", str(m), "--out", str(tmp_path / "o")]) == 1
    assert "a state the controller does not define" in capsys.readouterr().err
    assert main(["run", str(ctl), "--map", str(m), "--until", "nope"]) == 2
    assert "no event of that name" in capsys.readouterr().err
