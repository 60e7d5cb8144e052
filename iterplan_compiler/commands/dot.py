"""``iterc dot SPEC [NAME] [-o FILE.{dot,svg,png}] [--controller]``.

Draws any process or composite of SPEC (default: the last controller composite) in the style of
the paper's Fig. 2: controllable transitions dashed, uncontrollable solid.  ``--controller``
draws the synthesised controller of a controller composite instead of its controlled
composition.  SVG/PNG output needs Graphviz's ``dot`` program.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from iterplan_compiler import pipeline
from iterplan_compiler.backends.graphviz import RENDER_FORMATS, GraphvizError, to_dot
from iterplan_compiler.backends.graphviz import render as render_drawing
from iterplan_compiler.diagnostics import render
from iterplan_compiler.outputs import OutputError, refuse_overwrite_input
from iterplan_compiler.synthesis.driver import SOLVERS, Solver

HELP = "export a process, composite or controller as Graphviz"

#: Above this many transitions, rendering to SVG/PNG/PDF prints a "this may take long" note
#: (QA: 463 transitions took dot 4-6 s on a loaded 2-core machine, 6.6 k did not finish in 10 min).
LARGE_DRAWING = 500


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("spec", metavar="SPEC", help="the .lts specification file")
    parser.add_argument("name", metavar="NAME", nargs="?",
                        help="process or composite to draw (default: the last controller "
                             "composite, else the last definition)")
    parser.add_argument("-o", "--output", metavar="FILE",
                        help="write .dot/.gv, or render .svg/.png/.pdf (default: DOT to stdout)")
    parser.add_argument("--controller", action="store_true",
                        help="draw the synthesised controller of a controller composite")
    parser.add_argument("--plain", action="store_true",
                        help="draw every transition solid (ignore controllability)")
    parser.add_argument("--solver", choices=SOLVERS, default=Solver.SYMBOLIC.value,
                        help="GR(1) solver used with --controller (default: symbolic)")


def run(args: argparse.Namespace) -> int:
    """Draw; print diagnostics to stderr; return 0, 1 (errors) or 2 (usage)."""
    if args.output:
        suffix = Path(args.output).suffix.lower()
        if suffix not in (".dot", ".gv", *RENDER_FORMATS):
            print(f"iterc dot: cannot write {args.output}: use .dot, .gv, .svg, .png or .pdf",
                  file=sys.stderr)
            return 2
        try:
            refuse_overwrite_input(args.output, [args.spec])
        except OutputError as exc:
            print(f"iterc dot: {exc.message}", file=sys.stderr)
            return 1
        if not Path(args.output).parent.is_dir():
            print(f"iterc dot: cannot write {args.output}: no such directory "
                  f"'{Path(args.output).parent}'", file=sys.stderr)
            return 1
    drawing = pipeline.draw(args.spec, args.name, controller=args.controller,
                            solver=Solver(args.solver))
    lts, controllable, diags, sources = (drawing.lts, drawing.controllable, drawing.diagnostics,
                                         drawing.sources)
    if diags:
        print(render(diags, sources), file=sys.stderr)
    if lts is None:
        return 1
    text = to_dot(lts, controllable=None if args.plain else controllable)
    if not args.output:
        sys.stdout.write(text)
        return 0
    if Path(args.output).suffix.lower() in RENDER_FORMATS and \
            lts.num_transitions > LARGE_DRAWING:
        # Graphviz's layout is super-linear: a few thousand edges can take minutes and the
        # picture is unreadable anyway, so say why the command seems to hang.
        print(f"iterc dot: note: '{lts.name}' has {lts.num_states} states and "
              f"{lts.num_transitions} transitions; Graphviz may take a long time to lay it out "
              "(write .dot instead, or draw a smaller process)", file=sys.stderr)
    try:
        refuse_overwrite_input(args.output, list(sources))  # included files are known now
        render_drawing(text, args.output)
    except OutputError as exc:
        print(f"iterc dot: {exc.message}", file=sys.stderr)
        return 1
    except GraphvizError as exc:
        print(f"iterc dot: {exc}", file=sys.stderr)
        return 1
    except OSError as exc:
        print(f"iterc dot: cannot write {args.output}: {exc.strerror}", file=sys.stderr)
        return 1
    return 0
