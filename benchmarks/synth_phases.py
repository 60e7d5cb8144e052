"""Per-phase CPU seconds of one symbolic ``synthesize`` call, and the controller's size.

    python benchmarks/synth_phases.py FILE [FILE ...] [--composite Control] [--runs 1]
                                      [--macro auto|off]

Each file runs in its own process (``--one``).  The phases are timed with
``time.process_time`` by wrapping the functions that implement them (the stats' ``t_*``
entries are wall-clock, which on a shared, loaded machine is up to 2-8x the CPU time):

* ``prepare``  — ``encode.prepare`` and the leaf quotient / fluent-aligned recoding;
* ``encode``   — building the ``SymbolicGame`` (BDD encoding of the leaves);
* ``reach``    — symbolic reachability and restricting the relations to it;
* ``fixpoint`` — the GR(1) fixpoint (``fixpoint.gr1_winning``, or ``macro.solve_macro``
  with its exit relation; ``--macro off`` solves the full game);
* ``ranks``    — MTSA's rank layers (``symbolic_strategy.rank_layers``);
* ``build``    — the enumeration of the controller / director (without its rank layers);
* ``minimise`` — strong minimisation of the controller;
* ``synth``    — the whole ``synthesize`` call (so it also holds re-composition).

``strategy`` is the kind of controller built (``permissive``: MTSA's §3.6 controller,
``director``: one controllable move per state; docs/synthesis.md); ``states`` the controller's
states after minimisation.  Without ``--one`` a table of every file is printed.  Works on
trees without the director too (then ``strategy`` reads ``-``).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

# measure the tree this script is in, not whichever iterplan is installed
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

PHASES = ("prepare", "encode", "reach", "fixpoint", "ranks", "build", "minimise", "synth")


class _Clock:
    """CPU seconds per phase, accumulated by wrapped functions."""

    def __init__(self) -> None:
        self.cpu: dict[str, float] = dict.fromkeys(PHASES, 0.0)

    def wrap(self, phase: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        def timed(*args: Any, **kwargs: Any) -> Any:
            t = time.process_time()
            try:
                return fn(*args, **kwargs)
            finally:
                self.cpu[phase] += time.process_time() - t
        return timed


def _instrument(clock: _Clock) -> None:
    from iterplan_compiler.synthesis import driver, game, symbolic_game, symbolic_strategy

    game.quotient_leaves = clock.wrap("prepare", game.quotient_leaves)
    game.recode_leaves = clock.wrap("prepare", game.recode_leaves)
    driver.prepare = clock.wrap("prepare", driver.prepare)
    symbolic_game.SymbolicGame.__init__ = clock.wrap(  # type: ignore[method-assign]
        "encode", symbolic_game.SymbolicGame.__init__)
    cls = symbolic_game.SymbolicGame
    cls.reachable = clock.wrap("reach", cls.reachable)  # type: ignore[method-assign]
    cls.restrict = clock.wrap("reach", cls.restrict)  # type: ignore[method-assign]
    game.gr1_winning = clock.wrap("fixpoint", game.gr1_winning)
    if hasattr(game, "solve_macro"):  # this tree's macro steps (synthesis/macro.py)
        game.solve_macro = clock.wrap("fixpoint", game.solve_macro)
    symbolic_strategy.rank_layers = clock.wrap("ranks", symbolic_strategy.rank_layers)
    # the enumeration = the extraction entry points minus their rank layers
    for name in ("extract_gr1_strategy", "symbolic_controller"):  # this tree's, or older
        if hasattr(game, name):
            setattr(game, name, clock.wrap("build", getattr(game, name)))
            break
    driver._minimise = clock.wrap("minimise", driver._minimise)


def run_one(path: str, composite: str, macro: str = "auto") -> dict[str, Any]:
    import warnings

    warnings.simplefilter("ignore")
    from benchmarks.syntech15_bench import load_problem
    from iterplan_compiler.synthesis.driver import synthesize

    problem, why = load_problem(path, composite)
    if problem is None:
        return {"verdict": "error", "why": why}
    clock = _Clock()
    _instrument(clock)
    t = time.process_time()
    extra: dict[str, Any] = {}
    if macro != "auto":  # trees without macro steps know no such option
        from iterplan_compiler.synthesis.options import MacroSteps

        extra["macro"] = MacroSteps(macro)
    result = synthesize(problem, explain=False, **extra)
    clock.cpu["synth"] = time.process_time() - t
    clock.cpu["build"] -= clock.cpu["ranks"]  # rank layers run inside the extraction
    st = result.stats
    return {"verdict": "realizable" if result.realizable else "unrealizable",
            "strategy": str(st.get("strategy", "-")),
            "states": st.get("controller_states"), "cpu": clock.cpu}


def measure(path: Path, composite: str, macro: str = "auto") -> dict[str, Any]:
    proc = subprocess.run([sys.executable, __file__, "--one", str(path), "--composite",
                           composite, "--macro", macro], stdout=subprocess.PIPE, text=True,
                          check=False)
    lines = proc.stdout.strip().splitlines()
    return json.loads(lines[-1]) if lines else {"verdict": "crash"}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="*", type=Path)
    ap.add_argument("--composite", default="Control")
    ap.add_argument("--one", help=argparse.SUPPRESS)
    ap.add_argument("--runs", type=int, default=1, help="runs per file (the median is shown)")
    ap.add_argument("--macro", default="auto", choices=("auto", "off"),
                    help="macro steps of the symbolic solver (synthesis/macro.py)")
    args = ap.parse_args(argv)
    if args.one:
        print(json.dumps(run_one(args.one, args.composite, args.macro)))
        return 0
    head = ["file", "verdict", "strategy", "states", *PHASES]
    print("\t".join(head))
    for path in args.files:
        runs = [measure(path, args.composite, args.macro) for _ in range(args.runs)]
        runs.sort(key=lambda r: r.get("cpu", {}).get("synth", 0.0))
        r = runs[len(runs) // 2]
        cpu = r.get("cpu", {})
        row = [path.name, r["verdict"], r.get("strategy", "-"), str(r.get("states", "-")),
               *(f"{cpu[p]:.2f}" if p in cpu else "-" for p in PHASES)]
        print("\t".join(row), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
