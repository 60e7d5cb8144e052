"""Every command on the bundled examples: exit 0, deterministic output, outputs that other tools
(and our own front-end) read back."""

from __future__ import annotations

import importlib.util
import shutil
import sys

import pytest
from cli_helpers import EXAMPLES, GOLDEN_SPEC, assert_input_error, assert_no_crash, run_cli

from iterplan_compiler import pipeline
from iterplan_compiler.backends.jsonout import from_json
from iterplan_compiler.ir.lts import reachable
from iterplan_compiler.ir.minimise import bisimilar

FIRE = EXAMPLES / "fire_patrol.lts"
ALL_EXAMPLES = sorted(EXAMPLES.glob("*.lts"))


def test_examples_exist():
    assert FIRE.is_file() and len(ALL_EXAMPLES) >= 5


@pytest.mark.parametrize("spec", ALL_EXAMPLES, ids=lambda p: p.stem)
def test_check_every_example(spec, capsys):
    res = run_cli(capsys, "check", spec)
    assert_no_crash(res)
    assert res.code == 0, res.err
    assert f"{spec}: ok" in res.out
    assert "error[" not in res.err


def test_lts_stats_and_fsp(capsys):
    res = run_cli(capsys, "lts", FIRE, "--stats")
    assert res.code == 0, res.err
    assert res.out.startswith("FirePatrolSystem: states ")
    res = run_cli(capsys, "lts", FIRE, "Iterator", "--fsp")
    assert res.code == 0, res.err
    assert res.out.startswith("Iterator = ")


def test_synth_fire_patrol(capsys):
    res = run_cli(capsys, "synth", FIRE)
    assert_no_crash(res)
    assert res.code == 0, res.err
    assert "FirePatrol: realizable" in res.out
    assert "controller: 13 states" in res.out  # the paper's Fig. 1 controller


def test_verify_prints_counterexample_from_the_initial_state(capsys):
    # `assert HasNextInfinitelyOften = (HasNext)` is a *state* formula when checked directly
    # (it becomes []<> only as a controllerSpec liveness goal): HasNext is false after the
    # first action, takeoff, so the check fails with a trace that starts there.
    res = run_cli(capsys, "verify", FIRE, "--assert", "HasNextInfinitelyOften",
                  "--on", "FirePatrolSystem")
    assert_no_crash(res)
    assert res.code == 1
    assert "Violation of LTL property HasNextInfinitelyOften" in res.out
    trace = res.out.split("Trace to property violation in FirePatrolSystem:\n", 1)[1]
    assert trace.splitlines()[0].strip() == "takeoff"
    assert "note: HasNextInfinitelyOften has no temporal operator" in res.out


def test_verify_liveness_of_the_synthesised_system(tmp_path, capsys):
    # The same goal written as []<> holds on the controlled system (fair runs), and the spec's
    # include of the stdlib still resolves from a copy outside examples/.
    spec = tmp_path / "fire_gf.lts"
    spec.write_text(FIRE.read_text(encoding="utf-8") + "\nassert GF = []<>HasNext\n",
                    encoding="utf-8")
    res = run_cli(capsys, "verify", spec, "--assert", "GF", "--on", "FirePatrolSystem")
    assert_no_crash(res)
    assert res.code == 0, res.err
    assert "assert GF on FirePatrolSystem: No LTL Property violations detected." in res.out


@pytest.fixture(scope="module")
def fire_outputs(tmp_path_factory):
    """`iterc compile FIRE --emit KIND` for every kind, run once for the module."""
    from iterplan_compiler import cli

    out_dir = tmp_path_factory.mktemp("fire")
    outputs = {}
    for kind, suffix in (("py", ".py"), ("dot", ".dot"), ("fsp", ".lts"), ("json", ".json")):
        path = out_dir / f"fire_ctl{suffix}"
        assert cli.main(["compile", str(FIRE), "-o", str(path)]) == 0
        outputs[kind] = path.read_text(encoding="utf-8")
    return out_dir, outputs


def test_compile_outputs_are_deterministic_and_relative(fire_outputs, capsys):
    out_dir, outputs = fire_outputs
    for text in outputs.values():
        assert str(EXAMPLES) not in text and str(out_dir) not in text
    for kind in ("py", "fsp"):  # two fresh runs (each one synthesises again), to stdout
        text = outputs[kind]
        res = run_cli(capsys, "compile", FIRE, "--emit", kind)
        assert res.code == 0, res.err
        assert res.out == text, f"--emit {kind} differs between runs / between -o and stdout"


def test_compiled_module_runs(fire_outputs, tmp_path):
    _, outputs = fire_outputs
    path = tmp_path / "fire_ctl_mod.py"
    path.write_text(outputs["py"], encoding="utf-8")
    spec = importlib.util.spec_from_file_location("fire_ctl_mod", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules["fire_ctl_mod"] = mod
    try:
        spec.loader.exec_module(mod)
    finally:
        sys.modules.pop("fire_ctl_mod", None)
    ctl = mod.make_controller()
    assert ctl.enabled_controllable() == ["takeoff"]
    ctl.step("takeoff")
    ctl.step("takeoff.ended")
    assert ctl.enabled_controllable() == ["has.next"]


def test_emitted_fsp_and_json_describe_the_same_controller(fire_outputs, tmp_path):
    out_dir, outputs = fire_outputs
    lts_json, controllable = from_json(outputs["json"])
    assert "has.next" in controllable and "y.next" not in controllable
    model, diags = pipeline.load_model(str(out_dir / "fire_ctl.lts"), text=outputs["fsp"])
    assert model is not None and not any(d.is_error for d in diags), diags
    (name,) = model.processes
    lts_fsp, diags = model.build_lts(name)
    assert lts_fsp is not None, diags
    assert lts_fsp.num_states == lts_json.num_states == 13
    assert bisimilar(lts_fsp, lts_json)
    # The DOT output draws the same transitions: one edge line per transition.
    edges = [ln for ln in outputs["dot"].splitlines() if " -> " in ln and "__start" not in ln]
    assert len(edges) == len(reachable(lts_json).transitions)


dot_missing = pytest.mark.skipif(shutil.which("dot") is None,
                                 reason="Graphviz `dot` is not installed")


@dot_missing
@pytest.mark.parametrize("suffix,magic", [(".svg", b"<?xml"), (".png", b"\x89PNG"),
                                          (".pdf", b"%PDF")])
def test_dot_renders(suffix, magic, tmp_path, capsys):
    out = tmp_path / f"controller{suffix}"
    res = run_cli(capsys, "dot", FIRE, "--controller", "-o", out)
    assert res.code == 0, res.err
    data = out.read_bytes()
    assert data.startswith(magic) or (suffix == ".svg" and b"<svg" in data[:400])
    if suffix == ".svg":
        assert b"take.photo" in data and b"stroke-dasharray" in data  # dashed = controllable


def test_dot_default_and_named(capsys):
    res = run_cli(capsys, "dot", GOLDEN_SPEC)
    assert res.code == 0, res.err
    assert res.out.startswith('digraph "Patrol"')
    res = run_cli(capsys, "dot", GOLDEN_SPEC, "OnlyPatrolled")
    assert res.code == 0, res.err
    assert "ERROR [shape=box" in res.out and '-> ERROR [label="go.next"' in res.out


@dot_missing
def test_dot_warns_before_a_long_layout(tmp_path, capsys, monkeypatch):
    from iterplan_compiler.commands import dot as dot_command

    monkeypatch.setattr(dot_command, "LARGE_DRAWING", 5)
    res = run_cli(capsys, "dot", GOLDEN_SPEC, "-o", tmp_path / "p.svg")
    assert res.code == 0, res.err
    assert "note: 'Patrol' has" in res.err and "may take a long time" in res.err
    res = run_cli(capsys, "dot", GOLDEN_SPEC, "-o", tmp_path / "p.dot")  # no layout, no note
    assert res.code == 0 and "note:" not in res.err


def test_both_solvers_compile_the_same_controller(fire_outputs, capsys):
    # The canonical renumbering makes the emitted controller independent of the solver.
    _, outputs = fire_outputs
    res = run_cli(capsys, "compile", FIRE, "--emit", "json", "--solver", "explicit")
    assert res.code == 0, res.err
    assert res.out == outputs["json"]


def test_verify_state_limit_is_a_diagnostic(capsys):
    res = run_cli(capsys, "verify", FIRE, "--assert", "VisitCondition", "--on",
                  "FirePatrolSystem", "--max-states", "3")
    # --max-states (limits.py) bounds composition, formula automata and the model-checking
    # product; whichever is built first reports it (E0402 composition, E0606 formula automaton)
    try:
        m = assert_input_error(res, FIRE, code="E0402", located=True)
    except AssertionError:
        m = assert_input_error(res, FIRE, code="E0606", located=True)
    assert "exceeds 3 states" in m["msg"] and "--max-states" in m["msg"]
