"""Seeds that mean something (issue #15): each seed varies the region's placement, the launch
cell and heading (and, through RunConfig.seed, the random order); sorters share the layout."""

from __future__ import annotations

import csv

from iterplan_compiler import cli
from iterplan_compiler.experiments import sweeps
from iterplan_compiler.experiments.sweeps import Case, layout


def test_seeds_vary_placement_and_start_but_not_between_sorters():
    lays = [layout(Case("fig3c", 713, 25, "distance", s)) for s in range(30)]
    assert len({lay.offset for lay in lays}) > 10
    assert len({lay.home for lay in lays}) > 3
    assert len({round(lay.heading, 6) for lay in lays}) == 30
    assert all(layout(Case("fig3c", 713, 25, srt, 7)) == lays[7]
               for srt in sweeps.SORTERS)


def test_every_seeded_region_fits_its_universe():
    for count in (10, 61, 300):
        for seed in range(30):
            case = Case("fig3c", 713, count, "tour", seed)
            sweeps.check_case(case)
            data = sweeps.case_map_data(case)
            cells = data["sensors"]["cover"]
            assert len(cells) == count
            assert all(r * data["cols"] + c < 713 for c, r in cells)


def test_rerun_skips_finished_rows_and_fig3a_writes_its_csv(tmp_path, capsys):
    args = ["experiment", "fig3c", "--quick", "--seeds", "1", "--sorters", "last",
            "--out", str(tmp_path), "--no-progress"]
    assert cli.main(args) == 0
    first = (tmp_path / "fig3c.csv").read_text()
    capsys.readouterr()
    assert cli.main(args) == 0
    assert "2 of 2 runs already done" in capsys.readouterr().err
    assert (tmp_path / "fig3c.csv").read_text() == first
    # a wider sweep keeps the finished rows and adds the new ones
    assert cli.main(["experiment", "fig3c", "--quick", "--seeds", "1", "--sorters",
                     "last,distance", "--out", str(tmp_path), "--no-progress"]) == 0
    rows = list(csv.DictReader((tmp_path / "fig3c.csv").open()))
    assert sorted({r["sorter"] for r in rows}) == ["distance", "last"]
    assert cli.main(["experiment", "fig3a", "--quick", "--sizes", "144", "--out",
                     str(tmp_path)]) == 0
    fig3a = list(csv.DictReader((tmp_path / "fig3a.csv").open()))
    assert [r["universe"] for r in fig3a] == ["144"] and float(fig3a[0]["loop_s"]) > 0


def test_fig3b_warmup_and_heading_flags_and_rows_from_older_csvs(tmp_path, capsys):
    """--warmup measures the loops after the first (the first loop's time is kept as a
    column); a results CSV written before the column existed is still resumed from."""
    args = ["experiment", "fig3b", "--quick", "--seeds", "1", "--sorters", "last",
            "--sizes", "144", "--fast-skip", "--headings", "grid", "--heading-choice",
            "repeat", "--warmup", "1", "--out", str(tmp_path), "--no-progress"]
    assert cli.main(args) == 0
    rows = list(csv.DictReader((tmp_path / "fig3b.csv").open()))
    assert len(rows) == 1 and rows[0]["warmup"] == "1"
    assert float(rows[0]["first_loop"]) > float(rows[0]["duration"]) > float(rows[0]["ideal"])
    summary = list(csv.DictReader((tmp_path / "fig3b_summary.csv").open()))
    assert float(summary[0]["first_loop_pct"]) > float(summary[0]["overhead_pct"])
    # an older CSV without the new columns: its runs count as done
    old = [{k: v for k, v in r.items() if k not in ("first_loop", "warmup")} for r in rows]
    with (tmp_path / "fig3b.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(old[0]))
        w.writeheader()
        w.writerows(old)
    capsys.readouterr()
    assert cli.main(args) == 0
    assert "1 of 1 runs already done" in capsys.readouterr().err
    assert cli.main(args[:-5] + ["--warmup=-1", "--out", str(tmp_path)]) == 2
