"""The front-end solves through the injected ``synthesis`` object (ir/solving.py), never by
importing the synthesis layer: without one, a build that needs solving reports E0909; with a
fake one, the fake is what runs; through the pipeline, the real driver runs."""

from __future__ import annotations

from dataclasses import dataclass, field

from iterplan_compiler import frontend, pipeline
from iterplan_compiler.ir.lts import LTS, make_lts
from iterplan_compiler.ir.model import SynthesisProblem
from iterplan_compiler.ir.solving import Synthesis

SPEC = """
Plant = (go -> done -> Plant | fail -> Plant).
Other = (done -> Other).
fluent Done = <done, {go, fail}>
assert GDone = Done
controllerSpec G = { liveness = {GDone} controllable = {go, fail} }
controller ||C = (Plant)~{G}.
||Sys = (C || Other).
checkCompatibility ||Compat = (Plant)~{G}.
plant ||P = (Plant)~{G}.
"""


class InputError(Exception):
    """The fake's "bad input" exception."""


@dataclass(frozen=True)
class FakeResult:
    realizable: bool
    controller: LTS | None
    composition: LTS | None
    explanation: str = ""


@dataclass
class FakeSynthesis:
    """Records the problems it is asked about; its controller only ever does ``go, done``."""

    calls: list[tuple[str, str]] = field(default_factory=list)
    fail: bool = False

    @property
    def input_errors(self) -> tuple[type[Exception], ...]:
        return (InputError,)

    def synthesize(self, problem: SynthesisProblem) -> FakeResult:
        self.calls.append(("synthesize", problem.name))
        if self.fail:
            raise InputError("the fake refuses")
        ctl = make_lts("C", 2, [(0, "go", 1), (1, "done", 0)], {"go", "done", "fail"})
        return FakeResult(True, ctl, ctl)

    def check_compatibility(self, problem: SynthesisProblem) -> tuple[bool, str]:
        self.calls.append(("check_compatibility", problem.name))
        return False, "fake: NOT compatible"

    def plant_components(self, problem: SynthesisProblem) -> tuple[LTS, ...]:
        self.calls.append(("plant_components", problem.name))
        return tuple(problem.plant)


def _load(tmp_path, synthesis: Synthesis | None):
    path = tmp_path / "inject.lts"
    path.write_text(SPEC)
    model, diags = frontend.load(str(path), synthesis=synthesis)
    assert model is not None and not [d for d in diags if d.is_error], diags
    return model


def test_without_synthesis_a_build_that_solves_reports_e0909(tmp_path):
    model = _load(tmp_path, None)
    for name in ("C", "Sys", "Compat", "P"):
        lts, diags = model.build_lts(name)
        assert lts is None, name
        assert [d.code for d in diags if d.is_error] == ["E0909"], (name, diags)
        assert "not available in this build step" in diags[0].message
    # what needs no solving still works: plain processes, the problem, the unsolved plant
    assert model.build_lts("Other")[0] is not None
    assert model.synthesis_problem("C")[0] is not None
    lts, diags = model.build_lts("Sys", solve=False)
    assert lts is not None and not diags


def test_the_injected_object_is_what_solves(tmp_path):
    fake = FakeSynthesis()
    model = _load(tmp_path, fake)
    sys_lts, diags = model.build_lts("Sys")
    assert sys_lts is not None and not diags
    # Sys = C || Other with the fake's controller: `fail` never happens
    assert "fail" not in {a for _, a, _ in sys_lts.transitions}
    compat, cdiags = model.build_lts("Compat")
    assert compat is not None and [d.code for d in cdiags] == ["W0903"]
    assert model.build_lts("P")[0] is not None
    assert fake.calls == [("synthesize", "C"), ("check_compatibility", "Compat"),
                          ("plant_components", "P")]


def test_input_errors_of_the_injected_object_are_diagnostics(tmp_path):
    model = _load(tmp_path, FakeSynthesis(fail=True))
    lts, diags = model.build_lts("Sys")
    assert lts is None
    assert [d.code for d in diags] == ["E0901"] and "the fake refuses" in diags[0].message


def test_the_pipeline_injects_the_driver(tmp_path):
    path = tmp_path / "inject.lts"
    path.write_text(SPEC)
    model, diags = pipeline.load_model(path)
    assert model is not None and not diags
    lts, bdiags = model.build_lts("Sys")
    assert lts is not None and not [d for d in bdiags if d.is_error], bdiags
    assert isinstance(pipeline.SYNTHESIS, pipeline.DriverSynthesis)
    elab = pipeline.load(path)
    assert pipeline.build(elab, "Sys").lts is not None
