"""Every bundled iterator example, compiled and flown with ``iterc run`` (in-process) on its
bundled map on the simulator: exit 0 and the task's behaviour, read back from ``events.csv``.

The behaviour checks are the example tests' own (``tests/examples/behaviour.py``); this file
only adds the glue from ``events.csv`` to their event log and the checks for the two tasks
that need the map's sensor rules (``dynamic`` in find_nemo.json, ``derived`` in
search_and_map.json), which ``iterc run`` must serve itself.
"""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from iterplan_compiler.cli import main
from iterplan_compiler.experiments.catalog import examples_dir
from iterplan_compiler.experiments.missions import LogEvent
from iterplan_compiler.pipeline import compile_spec
from iterplan_compiler.runtime.mapfile import load_map, parse_cell_name
from tests.examples.behaviour import cells, check_cover, check_fire_patrol, check_ordered_patrol

#: example -> extra `iterc run` flags (how long the mission is)
RUNS = {
    "fire_patrol": [],                              # one iterator pass (default --passes 1)
    "cover": [],
    "find_nemo": [],
    "ordered_patrol": ["--until", "visited.p.0:3"],  # p.0 p.1 p.2 p.0 p.1 p.2 p.0
    "search_and_map": ["--until", "restart"],        # search, map, land
}


def events_log(path: Path, grid) -> list[LogEvent]:
    """``events.csv`` -> controller events as the example checks read them: ``arrived`` and
    actions at a location (``take.photo``, ``store.target``, ``visited.*``) carry the cell of
    the last arrival (the planner's ``arrived`` entry, which precedes the controller's)."""
    out: list[LogEvent] = []
    here = -1
    with open(path, newline="") as fh:
        for row in csv.DictReader(fh):
            kind, label = row["kind"], row["label"]
            if kind == "p" and label.startswith("arrived") and row["cell"]:
                here = parse_cell_name(grid, row["cell"])
            if kind not in ("c", "u"):
                continue
            at_cell = label in ("arrived", "take.photo", "store.target") or \
                label.startswith("visited.")
            out.append(LogEvent(float(row["t"]), label, here if at_cell else -1,
                                float(row["east"]), float(row["north"])))
    return out


@pytest.fixture(scope="module")
def flown(tmp_path_factory):
    """Compile each example once and fly it; returns name -> (exit code, log, grid, stdout)."""
    root = tmp_path_factory.mktemp("examples_run")
    cache: dict[str, tuple] = {}

    def fly(name: str, capsys):
        if name not in cache:
            out = compile_spec(examples_dir() / f"{name}.lts")
            assert out.text is not None, out.diagnostics
            ctl = root / f"{name}_ctl.py"
            ctl.write_text(out.text)
            run_dir = root / name
            map_path = examples_dir() / f"{name}.json"
            rc = main(["run", str(ctl), "--map", str(map_path), "--out", str(run_dir),
                       "--ideal-compute", "--quiet", "--no-plot", *RUNS[name]])
            text = capsys.readouterr()
            grid = load_map(map_path)
            log = events_log(run_dir / "events.csv", grid) if rc == 0 else []
            cache[name] = (rc, log, grid, text.out + text.err)
        return cache[name]
    return fly


@pytest.mark.parametrize("name", sorted(RUNS))
def test_example_flies_with_iterc_run(flown, capsys, name):
    rc, log, grid, text = flown(name, capsys)
    assert rc == 0, text
    assert "mission completed" in text
    assert log and log[0].label == "takeoff"
    if name == "fire_patrol":
        check_fire_patrol(log, grid)
    elif name == "cover":
        check_cover(log, grid)
    elif name == "ordered_patrol":
        check_ordered_patrol(log, grid, 3)
        assert len([e for e in log if e.label.startswith("visited.p.")]) == 7
    elif name == "find_nemo":
        check_find_nemo(log, grid)
    else:
        check_search_and_map(log, grid)


def check_find_nemo(log: list[LogEvent], grid) -> None:
    """Every region cell visited; Nemo (map: ``yes_answers`` 2) is photographed exactly twice at
    each of its cells, right after a ``yes.nemo``, and then the plane moves on (no livelock)."""
    roi = {int(c) for c in grid.sensors["roi"]}
    nemo = {int(c) for c in grid.sensors["nemo"]}
    assert grid.dynamic["nemo"].yes_answers == 2
    assert set(cells(log, "arrived")) == roi
    assert sorted(cells(log, "take.photo")) == sorted(c for c in nemo for _ in range(2))
    for k, e in enumerate(log):
        if e.label == "take.photo":
            assert log[k - 1].label == "yes.nemo"
    assert sum(e.label == "yes.nemo" for e in log) == 2 * len(nemo)


def check_search_and_map(log: list[LogEvent], grid) -> None:
    """Search until the target is seen, store it, then photograph exactly the cells 8-adjacent
    to it (map: derived sensor ``adjacent``), flying nowhere else, then land."""
    target = int(grid.sensors["target"][0])
    assert cells(log, "store.target") == [target]
    i = next(k for k, e in enumerate(log) if e.label == "store.target")
    assert "take.photo" not in {e.label for e in log[:i]}
    tr, tc = divmod(target, grid.cols)
    ring = {r * grid.cols + c for r in range(tr - 1, tr + 2) for c in range(tc - 1, tc + 2)
            if 0 <= r < grid.rows and 0 <= c < grid.cols}
    assert set(cells(log[i:], "take.photo")) == ring
    assert set(cells(log[i + 1:], "arrived")) <= ring
    assert [e.label for e in log[-3:]] == ["land", "landed", "restart"]
