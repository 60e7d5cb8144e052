"""Shared helpers for the back-end tests: hand-made controllers, module loading, golden files.

Golden files live in ``tests/data/golden/``.  To rewrite them from the current output, run the
tests with ``ITERPLAN_UPDATE_GOLDEN=1`` and review the diff.
"""

from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path
from types import ModuleType

from iterplan_compiler.ir.lts import LTS, make_lts

GOLDEN_DIR = Path(__file__).resolve().parents[1] / "data" / "golden"
UPDATE_GOLDEN = os.environ.get("ITERPLAN_UPDATE_GOLDEN", "") not in ("", "0")

# A Fire-Patrol-like controller written by hand (paper §III): iterate over locations, ask
# whether the next one must be patrolled, fly there, check for fire, photograph fires.
FIRE_PATROL_CONTROLLABLE = frozenset({
    "has.next", "remove.next", "reset", "is.next.inP", "go.next", "is.fire", "take.photo",
})


def fire_patrol() -> LTS:
    """Return the hand-made Fire Patrol controller (12 states)."""
    t = [
        (0, "has.next", 1),
        (1, "y.next", 2), (1, "n.next", 11),
        (2, "is.next.inP", 3),
        (3, "yes.next.inP", 4), (3, "no.next.inP", 10),
        (4, "go.next", 5),
        (5, "arrived", 6),
        (6, "is.fire", 7),
        (7, "yes.fire", 8), (7, "no.fire", 10),
        (8, "take.photo", 10),
        (10, "remove.next", 0),
        (11, "reset", 0),
    ]
    # State 9 is unused on purpose: the table must keep states without moves.
    return make_lts("FirePatrol", 12, t)


def toggle() -> LTS:
    """Return a 3-state controller with state names and a final state without moves."""
    t = [(0, "on", 1), (1, "ack", 0), (1, "fail", 2), (0, "stop", 2)]
    return make_lts("toggle-ctl", 3, t, alphabet={"unused.ev"},
                    state_names=("Idle", "Busy", "Done"))


TOGGLE_CONTROLLABLE = frozenset({"on", "stop"})


def load_module(text: str, directory: Path, name: str) -> ModuleType:
    """Write ``text`` to ``directory/name.py`` and import it as a fresh module."""
    path = directory / f"{name}.py"
    path.write_text(text, encoding="utf-8")
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    finally:
        sys.modules.pop(name, None)
    return module


def check_golden(actual: str, filename: str) -> None:
    """Assert ``actual`` equals the golden file (or rewrite it when updating)."""
    path = GOLDEN_DIR / filename
    if UPDATE_GOLDEN:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(actual, encoding="utf-8")
        return
    assert path.exists(), f"missing golden file {path}; run with ITERPLAN_UPDATE_GOLDEN=1"
    expected = path.read_text(encoding="utf-8")
    assert actual == expected, (
        f"{filename} differs from the golden file; if the change is intended, rerun with "
        "ITERPLAN_UPDATE_GOLDEN=1 and review the diff"
    )


# --- a stand-in for the front-end's Model and for synthesis, to test the driver and CLI --------

def fake_result(controller: LTS | None, explanation: str = ""):
    """A ``synthesis.driver.SynthesisResult`` with a given controller (None: unrealizable)."""
    from iterplan_compiler.synthesis.driver import Solver, SynthesisResult, SynthesisStats

    stats = SynthesisStats(Solver.SYMBOLIC, mode="gr1",
                           warnings=("fluent F: actions ['zz'] are not plant actions",),
                           controller_states=controller.num_states if controller else None)
    return SynthesisResult(controller is not None, controller, controller, explanation, stats)


def fake_load(model):
    """A stand-in for ``pipeline.load`` that returns ``model`` (or a front-end failure)."""
    from iterplan_compiler import pipeline

    def load(path, text=None):
        return pipeline.Elaborated(str(path), model, (), {str(path): model.source_text})

    return load


class FakeProblem:
    """Shaped like ``ir.model.SynthesisProblem`` (only the fields the driver reads)."""

    def __init__(self, name: str, controllable: frozenset[str], span, spec_name: str = "G"):
        self.name = name
        self.controllable = controllable
        self.span = span
        self.spec_name = spec_name


class FakeModel:
    """Shaped like the front-end's ``Model``: processes, and controller composites whose
    synthesis outcome is given (an LTS, or None for unrealizable)."""

    def __init__(self, path: str, text: str, processes: dict[str, LTS],
                 controllers: dict[str, tuple[LTS | None, frozenset[str]]]):
        from iterplan_compiler.diagnostics import Span
        from iterplan_compiler.ir.model import ControllerSpec

        self.source_path = path
        self.source_text = text
        self.processes = processes
        self.controllers = controllers
        self.spans = {n: Span(path, i + 2, 1) for i, n in enumerate(controllers)}
        self.controller_specs = {"G": ControllerSpec("G", span=Span(path, 1, 1))}

    def names(self) -> list[str]:
        return [*self.processes, *self.controllers]

    @property
    def composites(self) -> list[str]:
        return list(self.controllers)

    def controller_composites(self) -> list[str]:
        return list(self.controllers)

    def controllable(self, name: str) -> frozenset[str]:
        return self.controllers[name][1]

    def synthesis_problem(self, name: str):
        from iterplan_compiler.diagnostics import error
        if name not in self.controllers:
            return None, [error("E999", f"{name} is not a controller composite")]
        return FakeProblem(name, self.controllers[name][1], self.spans[name]), []

    def build_lts(self, name: str, unrealizable: str = "error", solve: bool = True):
        if name in self.processes:
            return self.processes[name], []
        return self.controllers[name][0], []


def fake_synthesize(problem, **_options):
    """Stand-in for ``synthesis.driver.synthesize`` reading the outcome off the problem."""
    model = FakeModel.current
    ctl = model.controllers[problem.name][0]
    return fake_result(ctl, "" if ctl else "the environment can keep y.next from happening")


FakeModel.current = None  # type: ignore[attr-defined]
