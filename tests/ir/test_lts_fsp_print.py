"""FSP printing of LTSs (MTSA export style)."""

from __future__ import annotations

from helpers_lts import E, cycle, lts

from iterplan_compiler.ir.fsp_print import format_label, lts_to_fsp, process_name
from iterplan_compiler.ir.lts import TAU


def test_cycle_prints_in_mtsa_style():
    text = lts_to_fsp(cycle("P", "a", "b"))
    assert text == "P = Q0,\n\tQ0\t= (a -> Q1),\n\tQ1\t= (b -> Q0).\n"


def test_grouping_error_stop_end_and_extension():
    m = lts("Exp", 4, [(0, "b", E), (0, "c", E), (0, "a", 1), (0, "d.1", 2), (1, TAU, 3)],
            alphabet={"z", "w.2"}, end={3})
    text = lts_to_fsp(m)
    assert text.splitlines() == [
        "Exp = Q0,",
        "\tQ0\t= (a -> Q1",
        "\t\t  |{b, c} -> ERROR",
        "\t\t  |d[1] -> Q2),",
        "\tQ1\t= (_tau -> Q3),",
        "\tQ2\t= STOP,",
        "\tQ3\t= END+{w[2], z}\\{_tau}.",
    ]


def test_labels_and_names():
    assert format_label("route.3.observe") == "route[3].observe"
    assert format_label("a.b") == "a.b"
    assert format_label(TAU) == "_tau"
    assert process_name("C_#NC#") == "C__NC_"
    assert process_name("plant") == "Plant"
    assert process_name("P(2)") == "P_2_"
    assert process_name("1x") == "P1x"
    assert process_name("Q3") == "Q3_"


def test_unreachable_states_are_not_printed():
    m = lts("R", 3, [(1, "a", 0), (0, "b", 2)], alphabet={"z"})
    assert lts_to_fsp(m) == "R = Q0,\n\tQ0\t= (b -> Q2),\n\tQ2\t= STOP+{a, z}.\n"


def test_output_is_deterministic():
    m = lts("M", 3, [(0, "x", 1), (0, "y", 2), (2, "x", 0)])
    assert lts_to_fsp(m) == lts_to_fsp(lts("M", 3, list(reversed(m.transitions))))


def test_hiding_never_follows_a_bare_stop():
    # `Q1 = STOP\{_tau}.` would parse as the label difference STOP \ {_tau}: the printer ends
    # the definition with a state that has moves instead (found by the round-trip property).
    text = lts_to_fsp(lts("R", 2, [(0, TAU, 1)]))
    assert text == "R = Q0,\n\tQ1\t= STOP,\n\tQ0\t= (_tau -> Q1)\\{_tau}.\n"
