"""The synthesis-time table: measurement in a child process, budget, formatting."""

from __future__ import annotations

import math

from iterplan_compiler.experiments import catalog, synthesis_table


def test_explicit_version_grows_while_iterator_version_does_not():
    cover = catalog.example_path("cover")
    it = synthesis_table.measure("cover", None, cover, cover.read_text(), "Cover", 120)
    assert it.status == "realizable" and it.states is not None
    path = catalog.example_path("fire_patrol_explicit")
    rows = [synthesis_table.measure("fire_patrol_explicit", n, path,
                                    catalog.explicit_fire_patrol(n), "ExplicitFirePatrol", 120)
            for n in (1, 2)]
    assert all(r.status == "realizable" for r in rows), rows
    assert rows[1].states > 2 * rows[0].states
    text = synthesis_table.format_table([it, *rows])
    assert "fire_patrol_explicit" in text and "any" in text
    csv = synthesis_table.rows_csv([it, *rows])
    assert csv.splitlines()[0] == "spec,n,status,load_s,synth_s,states"
    assert len(csv.splitlines()) == 4


def test_budget_cuts_a_synthesis_off():
    path = catalog.example_path("fire_patrol_explicit")
    row = synthesis_table.measure("fire_patrol_explicit", 9, path,
                                  catalog.explicit_fire_patrol(9), "ExplicitFirePatrol", 0.05)
    assert row.status == "timeout" and math.isnan(row.load_s)


def test_errors_are_rows_not_exceptions(tmp_path):
    bad = tmp_path / "bad.lts"
    row = synthesis_table.measure("bad", None, bad, "P = (a -> ", "C", 60)
    assert row.status == "error" and row.detail
