"""The compile driver on real synthesis (the front-end is stubbed: problems are built by hand).

This pins the contract between ``synthesis.driver.synthesize`` and the back-end: the emitted
module's table is exactly the synthesised controller, and unrealizable problems come back as
an E0901 diagnostic carrying synthesis's explanation.
"""

from __future__ import annotations

import pytest
from backends_helpers import load_module

from iterplan_compiler import pipeline
from iterplan_compiler.cli import main
from iterplan_compiler.diagnostics import Span
from iterplan_compiler.ir.formulas import Fluent, FluentProp
from iterplan_compiler.ir.lts import make_lts
from iterplan_compiler.ir.model import SynthesisProblem

CONTROLLABLE = frozenset({"has.next", "go.next", "remove.next", "reset"})
FLUENTS = (
    Fluent("Arrived", frozenset({"arrived"}), frozenset({"has.next"})),
    Fluent("YesNext", frozenset({"y.next"}), frozenset({"has.next"})),
)


def plant():
    """An iterator + UAV: after y.next the controller may fly (go.next) or skip (remove.next)."""
    return make_lts("Env", 6, [
        (0, "has.next", 1), (1, "y.next", 2), (1, "n.next", 3), (2, "go.next", 4),
        (2, "remove.next", 0), (4, "arrived", 5), (5, "remove.next", 0), (3, "reset", 0)])


class ProblemModel:
    """Front-end stand-in: composites map to hand-built synthesis problems."""

    def __init__(self, path: str):
        self.source_path = path
        self.source_text = None
        self.controller_specs = {}
        span = Span(path, 1, 1)
        common = dict(keywords=frozenset({"controller"}), plant=(plant(),), safety=(),
                      failures=(), fluents=FLUENTS, controllable=CONTROLLABLE, span=span)
        self.problems = {
            # GF Arrived, assuming GF YesNext: the controller must fly after y.next.
            "Visit": SynthesisProblem("Visit", assumptions=(FluentProp("YesNext"),),
                                      guarantees=(FluentProp("Arrived"),), **common),
            # GF Arrived without assumption: the iterator may answer n.next forever.
            "Hopeless": SynthesisProblem("Hopeless", assumptions=(),
                                         guarantees=(FluentProp("Arrived"),), **common),
        }

    source_text = "// stand-in\n"

    def names(self):
        return list(self.problems)

    @property
    def composites(self):
        return list(self.problems)

    def controller_composites(self):
        return list(self.problems)

    def controllable(self, name):
        return self.problems[name].controllable

    def synthesis_problem(self, name):
        return self.problems[name], []


@pytest.fixture
def spec(tmp_path, monkeypatch):
    path = tmp_path / "visit.lts"
    path.write_text("// stand-in\n", encoding="utf-8")
    monkeypatch.setattr(pipeline, "load", lambda p, text=None: pipeline.Elaborated(
        str(p), ProblemModel(str(p)), (), {str(p): ProblemModel.source_text}))
    return path


@pytest.mark.parametrize("solver", ["symbolic", "explicit"])
def test_module_table_equals_synthesised_controller(spec, tmp_path, solver):
    out = pipeline.compile_spec(spec, composite="Visit", solver=solver)
    assert out.text is not None, out.diagnostics
    mod = load_module(out.text, tmp_path, f"visit_{solver}")
    assert set(mod.TRANSITIONS) == set(out.controller.transitions)
    assert mod.TABLE.initial == out.controller.initial
    assert mod.CONTROLLABLE == CONTROLLABLE & out.controller.alphabet
    # Behaviour: after y.next the controller must fly, never skip.
    c = mod.make_controller()
    c.step("has.next")
    c.step("y.next")
    assert c.enabled_controllable() == ["go.next"]
    answers = iter(["y.next", "n.next", "y.next"])
    flown = []
    bindings = {"has.next": lambda: next(answers), "go.next": lambda: flown.append(1) or "arrived",
                "remove.next": lambda: None, "reset": lambda: None}
    c.reset()
    c.run(bindings, max_steps=13)
    assert len(flown) == 2


def test_unrealizable_reports_explanation(spec, capsys):
    assert main(["compile", str(spec), "-c", "Hopeless"]) == 1
    err = capsys.readouterr().err
    assert "error[E0901]" in err and "no controller exists for 'Hopeless'" in err
    assert "guarantee" in err  # synthesis's explanation is passed through


def test_default_composite_is_last_controller(spec, capsys):
    # The last controller composite (Hopeless) is the default, so this fails as unrealizable.
    assert main(["compile", str(spec)]) == 1
    assert "'Hopeless'" in capsys.readouterr().err
