"""`iterc demo` and `iterc experiment`: end to end on small sizes, and graceful degradation."""

from __future__ import annotations

import csv
import json

import pytest

from iterplan_compiler import cli
from iterplan_compiler.experiments import pipeline


def test_demo_end_to_end(tmp_path, capsys):
    out = tmp_path / "demo"
    rc = cli.main(["demo", "--out", str(out), "--quiet"])
    text = capsys.readouterr().out
    assert rc == 0, text
    assert "all patrol cells visited yes" in " ".join(text.split())
    assert "photos exactly at fires  yes" in text
    for f in ("fire_patrol_controller.py", "events.csv", "track.csv", "track.geojson",
              "summary.json", "flight.png"):
        assert (out / f).is_file(), f
    summary = json.loads((out / "summary.json").read_text())
    assert summary["cells outside P visited"] == 0
    assert (out / "flight.png").read_bytes()[:4] == b"\x89PNG"
    # compilation is deterministic: a second run regenerates the very same module
    before = (out / "fire_patrol_controller.py").read_text()
    assert cli.main(["demo", "--out", str(out), "--quiet"]) == 0
    assert (out / "fire_patrol_controller.py").read_text() == before


def test_demo_reports_a_failing_stage_without_traceback(tmp_path, capsys, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("synthesis exploded")

    monkeypatch.setattr(pipeline, "compile_spec", broken)
    rc = cli.main(["demo", "--out", str(tmp_path / "d")])
    err = capsys.readouterr().err
    assert rc == 1
    assert "synthesis exploded" in err and "Traceback" not in err


def test_experiment_fig3c_quick(tmp_path, capsys):
    out = tmp_path / "exp"
    rc = cli.main(["experiment", "fig3c", "--quick", "--seeds", "1", "--sorters",
                   "distance,last", "--out", str(out), "--no-progress"])
    text = capsys.readouterr().out
    assert rc == 0, text
    rows = list(csv.DictReader((out / "fig3c.csv").open()))
    assert len(rows) == 4 and not any(r["error"] for r in rows)
    for r in rows:
        assert float(r["duration"]) > float(r["ideal"]) > 0
        assert float(r["overhead_pct"]) > 0
    assert (out / "fig3c.png").read_bytes()[:4] == b"\x89PNG"
    assert not (out / "fig3c.partial.csv").exists()
    assert "overhead" in text


def test_experiment_usage_errors(tmp_path, capsys):
    assert cli.main(["experiment", "fig3b", "--sorters", "fastest", "--out",
                     str(tmp_path)]) == 2
    assert "unknown sorter" in capsys.readouterr().err
    assert cli.main(["experiment", "fig3b", "--seeds", "0", "--out", str(tmp_path)]) == 2


def test_scheduler_without_dask_is_a_clear_error(tmp_path, capsys):
    try:
        import dask.distributed  # noqa: F401
    except ImportError:
        pass
    else:
        pytest.skip("dask is installed; this checks the message when it is not")
    rc = cli.main(["experiment", "fig3c", "--quick", "--seeds", "1", "--sorters", "last",
                   "--scheduler", "tcp://127.0.0.1:1", "--out", str(tmp_path),
                   "--no-progress"])
    assert rc == 2
    assert "dask" in capsys.readouterr().err
