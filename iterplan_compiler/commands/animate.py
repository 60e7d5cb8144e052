"""``iterc animate SPEC [NAME] [--script FILE] [--spec G]`` — step through an LTS by hand.

Builds NAME like ``iterc lts`` (default: the last composite; a ``controller`` composite is the
synthesised controller) and shows, after every step, the trace so far, the current state(s),
the fluent values and the enabled actions, numbered, controllable ones marked ``*`` (the
controllable set of NAME's controllerSpec, of ``--spec G``, or of the spec's only
controllerSpec).  Commands: a number or an action name fires it; ``undo`` (``u``) steps back;
``save PATH`` (``s PATH``) writes the trace, one action a line; ``help``; ``quit`` (``q``,
Ctrl-D).  The state logic is :mod:`iterplan_compiler.ir.animator`; docs: ``docs/ltsa.md``.

On a terminal the prompt is prompt_toolkit's (completion of action names, history).  With
``--script FILE`` (or when standard input is not a terminal) the commands are read one a line
(``#`` starts a comment) and each is echoed as ``> command`` before the same screen text, so
tests and scripts see what a person sees; a command that cannot be carried out is an error
``FILE:LINE:1: error[E1311]`` and the exit code is 1.
"""

from __future__ import annotations

import argparse
import difflib
import sys
from collections.abc import Iterable

from iterplan_compiler import pipeline
from iterplan_compiler.diagnostics import Span, error, render
from iterplan_compiler.ir.animator import Animator

HELP = "animate a process or composite: pick actions, undo, save the trace"

E_BAD_COMMAND = "E1311"
E_NO_TARGET = "E0104"  # as `iterc lts`
E_NO_SPEC = "E1312"

COMMANDS_HELP = ("commands: NUMBER or ACTION fires it, u/undo, s/save PATH, h/help, q/quit")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("spec", help="FSP specification file (.lts)")
    parser.add_argument("name", nargs="?",
                        help="process or composite (default: the last composite)")
    parser.add_argument("--script", metavar="FILE",
                        help="read commands from FILE (one a line: an action or its number, "
                        "'undo', 'save PATH', 'quit') instead of the keyboard")
    parser.add_argument("--spec", dest="controller_spec", metavar="G",
                        help="mark the controllable actions of controllerSpec G")


class Session:
    """Carries out one command line on an :class:`Animator`; returns (message, quit)."""

    def __init__(self, animator):
        self.animator = animator

    def execute(self, line: str) -> tuple[str, bool]:
        from iterplan_compiler.ir.animator import AnimationError

        words = line.split()
        if not words:
            return "", False
        cmd, rest = words[0], words[1:]
        an = self.animator
        if cmd in ("q", "quit", "exit"):
            return "", True
        if cmd in ("h", "help", "?"):
            return COMMANDS_HELP, False
        if cmd in ("u", "undo"):
            if rest:
                raise AnimationError("undo takes no argument")
            if not an.undo():
                raise AnimationError("nothing to undo: the trace is empty")
            return "undone", False
        if cmd in ("s", "save"):
            if len(rest) != 1:
                raise AnimationError("save needs one file name: save PATH")
            try:
                an.save(rest[0])
            except OSError as e:
                raise AnimationError(f"cannot write {rest[0]}: {e.strerror or e}") from e
            n = len(an.trace)
            return f"saved {n} action{'s' if n != 1 else ''} to {rest[0]}", False
        if rest:
            raise AnimationError(f"unknown command '{line.strip()}'; {COMMANDS_HELP}")
        an.fire(cmd)
        return "", False


def _controllable(model, name: str, spec_name: str | None, spec_path: str):
    """(controllable set, where it came from, diagnostics)."""
    specs = model.controller_specs
    if spec_name is not None:
        if spec_name not in specs:
            close = difflib.get_close_matches(spec_name, list(specs), n=1)
            hint = f"; did you mean '{close[0]}'?" if close else (
                "; defined: " + (", ".join(specs) or "none"))
            return frozenset(), "", [error(E_NO_SPEC, f"no controllerSpec named "
                                           f"'{spec_name}'{hint}", Span(spec_path, 0, 0))]
        return specs[spec_name].controllable, f"controllerSpec {spec_name}", []
    if name in model.composites:
        c = model.controllable(name)
        if c:
            return c, f"{name}'s controllerSpec", []
    with_sets = [s for s in specs.values() if s.controllable]
    if len(with_sets) == 1:
        return with_sets[0].controllable, f"controllerSpec {with_sets[0].name}", []
    return frozenset(), "", []


def _build(args: argparse.Namespace) -> tuple[Animator | None, int]:
    """Load SPEC and build NAME → (animator, 0) or (None, exit code)."""
    elab = pipeline.load(args.spec)
    model = elab.model
    if not elab.ok or model is None:
        print(render([d for d in elab.diagnostics if d.is_error], elab.sources),
              file=sys.stderr)
        return None, 1
    whole = Span(args.spec, 0, 0)
    name = args.name or model.default_name()
    if name is None:
        print(render([error(E_NO_TARGET, "the spec defines no process or composite to "
                            "animate", whole)]), file=sys.stderr)
        return None, 1
    unknown = pipeline.unknown_name(elab, name)
    if unknown is not None:
        print(render([unknown]), file=sys.stderr)
        return None, 1
    controllable, origin, cdiags = _controllable(model, name, args.controller_spec, args.spec)
    if cdiags:
        print(render(cdiags), file=sys.stderr)
        return None, 1
    built = pipeline.build(elab, name, pipeline.BuildMode.SOLVE)
    lts = built.lts
    errs = [d for d in built.diagnostics if d.is_error]
    if errs or lts is None:
        print(render(errs, model.sources), file=sys.stderr)
        return None, 1
    return Animator(lts, frozenset(controllable) & lts.alphabet, model.fluents, name,
                    origin), 0


def run(args: argparse.Namespace) -> int:
    animator, code = _build(args)
    if animator is None:
        return code
    if args.script is not None:
        try:
            with open(args.script, encoding="utf-8") as f:
                lines = f.read().splitlines()
        except OSError as e:
            print(render([error("E0800", f"cannot read {args.script}: {e.strerror or e}",
                                Span(args.script, 0, 0))]), file=sys.stderr)
            return 1
        return scripted(animator, lines, args.script)
    if not sys.stdin.isatty():
        return scripted(animator, sys.stdin.read().splitlines(), "<stdin>")
    return interactive(animator)


def scripted(animator, lines: Iterable[str], source: str) -> int:
    """Run commands from ``lines``; the screen after each; exit 1 at the first bad one."""
    from iterplan_compiler.ir.animator import AnimationError

    session = Session(animator)
    print(animator.screen())
    for no, raw in enumerate(lines, 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        print(f"> {line}")
        try:
            message, done = session.execute(line)
        except AnimationError as e:
            sys.stdout.flush()
            print(render([error(E_BAD_COMMAND, str(e), Span(source, no, 1))]),
                  file=sys.stderr)
            return 1
        if message:
            print(message)
        if done:
            return 0
        print(animator.screen())
    return 0


def interactive(animator) -> int:
    """The prompt_toolkit loop (a real terminal)."""
    try:
        from prompt_toolkit import PromptSession
        from prompt_toolkit.completion import WordCompleter
        from prompt_toolkit.history import InMemoryHistory
    except ImportError:  # a dependency of iterplan, but an install may have skipped it
        print("iterc: error: the interactive animator needs prompt_toolkit: "
              "pip install prompt_toolkit (or give the commands with --script FILE)",
              file=sys.stderr)
        return 1

    from iterplan_compiler.ir.animator import AnimationError

    session = Session(animator)
    prompt: PromptSession[str] = PromptSession(history=InMemoryHistory())
    print(animator.screen())
    print(COMMANDS_HELP)
    while True:
        words = [*animator.enabled(), "undo", "save", "help", "quit"]
        try:
            line = prompt.prompt("animate> ", completer=WordCompleter(words, sentence=True))
        except (EOFError, KeyboardInterrupt):
            return 0
        try:
            message, done = session.execute(line)
        except AnimationError as e:
            print(f"error: {e}")
            continue
        if message:
            print(message)
        if done:
            return 0
        if line.strip():
            print(animator.screen())
