"""``iterc check``'s cheap semantic checks (commands/semantic_checks.py): each mistake is
reported at the offending token, and good specs get no new diagnostics."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from iterplan_compiler import cli

REPO = Path(__file__).resolve().parents[2]
DIAG = re.compile(r"^(?P<file>[^\s:]+):(?P<line>\d+):(?P<col>\d+): (?P<sev>error|warning)"
                  r"\[(?P<code>\w+)\]: (?P<msg>.*)$", re.M)

PLANT = """\
set Ctrl = {takeoff, land}
UAV = (takeoff -> fly -> land -> UAV).
fluent Landed = <land, takeoff>
"""


def run(capsys, *argv):
    capsys.readouterr()
    code = cli.main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def diags(err):
    return [(d["code"], d["sev"], int(d["line"]), int(d["col"]), d["msg"], Path(d["file"]).name)
            for d in DIAG.finditer(err)]


def where(text: str, token: str, nth: int = 0) -> tuple[int, int]:
    """1-based line and column of the ``nth`` occurrence of ``token`` in ``text``."""
    pos = -1
    for _ in range(nth + 1):
        pos = text.index(token, pos + 1)
    line = text.count("\n", 0, pos) + 1
    return line, pos - (text.rfind("\n", 0, pos) + 1) + 1


def write(tmp_path, text, name="spec.lts"):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


LIVENESS_AS_SAFETY = PLANT + """\
ltl_property L = []<> land
controllerSpec G = {
    safety = {L}
    liveness = {Landed}
    controllable = {Ctrl}
}
controller ||C = (UAV)~{G}.
"""


def test_liveness_formula_as_safety_property_is_an_error(tmp_path, capsys):
    spec = write(tmp_path, LIVENESS_AS_SAFETY)
    code, out, err = run(capsys, "check", spec)
    assert code == 1 and "ok" not in out
    ((c, sev, line, col, msg, _),) = diags(err)
    assert (c, sev) == ("E0605", "error")
    assert (line, col) == where(LIVENESS_AS_SAFETY, "L = ")
    assert "ltl_property L must be a safety formula" in msg and "(*)^w" in msg


def test_liveness_formula_as_safety_goal_is_not_realizable(tmp_path, capsys):
    spec = write(tmp_path, LIVENESS_AS_SAFETY)
    code, out, err = run(capsys, "synth", spec)
    assert code == 1
    assert "realizable" not in out
    assert "error[E0605]" in err


def test_liveness_formula_as_safety_goal_is_not_compiled(tmp_path, capsys):
    spec = write(tmp_path, LIVENESS_AS_SAFETY)
    code, _, err = run(capsys, "compile", spec, "-o", tmp_path / "ctrl.py")
    assert code == 1 and "error[E0605]" in err
    assert not (tmp_path / "ctrl.py").exists()


@pytest.mark.parametrize("formula", ["[](takeoff -> X fly)", "[](!land W fly)", "takeoff",
                                     "[](Landed -> !land)"])
def test_safety_formulas_are_not_flagged(tmp_path, capsys, formula):
    text = PLANT + f"ltl_property P = {formula}\n||S = (UAV || P).\n"
    code, out, err = run(capsys, "check", write(tmp_path, text))
    assert code == 0, err
    assert "E0605" not in err


def test_constraint_that_is_liveness_is_an_error(tmp_path, capsys):
    text = PLANT + "constraint K = <> fly\n||S = (UAV || K).\n"
    code, _, err = run(capsys, "check", write(tmp_path, text))
    assert code == 1
    assert [d[:2] for d in diags(err)] == [("E0605", "error")]
    assert "constraint K must be a safety formula" in err


MISSPELLED = PLANT + """\
controllerSpec G = {
    liveness = {Landed}
    controllable = {takeoff, lnad}
}
controller ||C = (UAV)~{G}.
"""


def test_misspelled_controllable_action_is_reported_at_the_token(tmp_path, capsys):
    code, out, err = run(capsys, "check", write(tmp_path, MISSPELLED))
    assert code == 0 and "ok" in out  # a warning: MTSA accepts it
    ((c, sev, line, col, msg, _),) = diags(err)
    assert (c, sev) == ("W0704", "warning")
    assert (line, col) == where(MISSPELLED, "lnad")
    assert "'lnad' is not an action of any process (did you mean 'land'?)" in msg


def test_controllable_set_from_a_library_is_not_a_misspelling(capsys):
    # uav.lts's UAVC lists land/restart; Fire Patrol's plant does not use them
    code, _, err = run(capsys, "check", REPO / "examples" / "fire_patrol.lts")
    assert code == 0
    assert "W0704" not in err and "W0905" not in err


FLUENT = PLANT + """\
fluent Flying = <takeof, land>
assert Up = []<> Flying
controllerSpec G = {
    liveness = {Landed}
    controllable = {Ctrl}
}
controller ||C = (UAV)~{G}.
"""


def test_fluent_action_not_in_the_plant_is_w501(tmp_path, capsys):
    code, _, err = run(capsys, "check", write(tmp_path, FLUENT))
    assert code == 0
    ((c, sev, line, col, msg, _),) = diags(err)
    assert (c, sev) == ("W0905", "warning")
    assert (line, col) == where(FLUENT, "takeof,")
    assert "fluent Flying: action 'takeof' is not an action of any plant" in msg
    assert "did you mean 'takeoff'?" in msg


def test_fluent_without_synthesis_is_checked_against_the_processes(tmp_path, capsys):
    text = "P = (a -> b -> P).\nfluent F = <a, c>\nassert A = []<> F\n"
    code, _, err = run(capsys, "check", write(tmp_path, text))
    assert code == 0
    ((c, _, line, col, msg, _),) = diags(err)
    assert (c, line, col) == ("W0905", 2, 16) and "not an action of any process" in msg


def test_missing_set_needed_by_an_included_library(tmp_path, capsys):
    text = (REPO / "examples" / "fire_patrol.lts").read_text(encoding="utf-8")
    text = re.sub(r"^set HereActions .*$", "", text, flags=re.M)
    spec = write(tmp_path, text, "fire_patrol.lts")
    code, out, err = run(capsys, "check", spec)
    assert code == 1 and "ok" not in out
    ((c, sev, line, col, msg, file),) = [d for d in diags(err) if d[1] == "error"]
    lib = (REPO / "stdlib" / "sensors.lts").read_text(encoding="utf-8")
    assert (c, sev, file) == ("E0209", "error", "sensors.lts")
    assert (line, col) == where(lib, "HereActions}")
    assert "set 'HereActions' is used by the included file sensors.lts" in msg
    inc_line, inc_col = where(text, '"sensors.lts"')
    assert f"fire_patrol.lts:{inc_line}:{inc_col}: note: 'sensors.lts' is included here" in err


def test_unused_library_fragment_needs_no_set(capsys):
    # cover.lts includes sensors.lts without HereActions and never uses AtLocation
    code, _, err = run(capsys, "check", REPO / "examples" / "cover.lts")
    assert code == 0 and "E0209" not in err


@pytest.mark.parametrize("example", sorted((REPO / "examples").glob("*.lts")),
                         ids=lambda p: p.name)
def test_bundled_examples_get_no_new_diagnostics(example, capsys):
    code, _, err = run(capsys, "check", example)
    assert code == 0
    assert not {"E0605", "W0704", "W0905", "E0209"} & {d[0] for d in diags(err)}
