"""Front-end of the iterplan compiler: FSP text → immutable :class:`~iterplan_compiler.ir.model.Model`.

Entry point: :func:`load`.  Stages: :mod:`.parse` (Lark LALR grammar → :mod:`.syntax` AST,
all syntax errors reported), :mod:`.includes` (``include "file.lts"``), :mod:`.elaborate`
(tables, fluents, formulas, specs; lazy LTS building via :mod:`.processes` and the composer
of :mod:`iterplan_compiler.ir.compose`).

The front-end never reaches up to the solver layer: building a composite that needs
solving uses the ``synthesis`` object passed to :func:`load` / :func:`elaborate_spec`
(interface :class:`~iterplan_compiler.ir.solving.Synthesis`; the pipeline passes the real
one, :func:`iterplan_compiler.pipeline.load_model`).  Without it such a build reports E0909.
"""

from __future__ import annotations

from pathlib import Path

from iterplan_compiler import limits
from iterplan_compiler.diagnostics import Diagnostic, Span, error, has_errors
from iterplan_compiler.frontend.elaborate import elaborate
from iterplan_compiler.frontend.errors import too_deep
from iterplan_compiler.frontend.includes import expand_includes
from iterplan_compiler.frontend.source import read_spec, text_binary_at
from iterplan_compiler.frontend.syntax import SpecFile
from iterplan_compiler.frontend.syntax_cache import parse_text
from iterplan_compiler.ir.model import Model
from iterplan_compiler.ir.solving import Synthesis

__all__ = ["elaborate_spec", "load", "load_with_sources", "not_text", "parse_file", "too_deep"]


def parse_file(path: str, text: str | None = None
               ) -> tuple[SpecFile | None, list[Diagnostic], dict[str, str]]:
    """Parse (with includes expanded) → ``(SpecFile, diagnostics, sources)``."""
    diags: list[Diagnostic] = []
    if text is None:
        try:
            read = read_spec(path)
        except OSError as e:
            return None, [error("E0800", f"cannot read {path}: {e.strerror or e}",
                                Span(path, 0, 0))], {}
        if isinstance(read, tuple):
            return None, [not_text(path, read)], {}
        text = read
    where = text_binary_at(text)
    if where is not None:
        return None, [not_text(path, where)], {}
    sources = {path: text}
    limits.progress(f"parsing {Path(path).name}", 0)
    try:
        spec, ds = parse_text(text, path)
        diags.extend(ds)
        spec = expand_includes(spec, sources, diags)
    except RecursionError:  # the syntax-tree walk is recursive (see too_deep)
        return None, [too_deep(path)], sources
    return spec, diags, sources


def load(path: str, text: str | None = None, *, synthesis: Synthesis | None = None
         ) -> tuple[Model | None, list[Diagnostic]]:
    """Parse and elaborate a spec file.

    Returns ``(model, diagnostics)``; ``model`` is ``None`` when the file could not be read or
    has syntax errors (elaboration errors still give a model, so callers can inspect what is
    well-formed, but ``has_errors(diagnostics)`` is then true).  ``synthesis`` solves the
    controller composites that building a machine needs (None: those builds report E0909).
    """
    model, diags, _ = load_with_sources(path, text, synthesis=synthesis)
    return model, diags


def load_with_sources(path: str, text: str | None = None, *,
                      synthesis: Synthesis | None = None
                      ) -> tuple[Model | None, list[Diagnostic], dict[str, str]]:
    """:func:`load`, also returning ``sources`` (file name → text of the file and of every
    include) so that callers can render diagnostics with source lines even when ``model`` is
    ``None`` (syntax errors) without parsing the file twice."""
    spec, diags, sources = parse_file(path, text)
    if spec is None or has_errors(diags):
        return None, diags, sources
    model, ds = elaborate_spec(spec, sources, path, synthesis=synthesis)
    return model, diags + ds, sources


def elaborate_spec(spec: SpecFile, sources: dict[str, str], path: str, *,
                   synthesis: Synthesis | None = None
                   ) -> tuple[Model | None, list[Diagnostic]]:
    """Elaborate a parsed file (``sources[path]`` is its text) into a :class:`Model`;
    ``synthesis`` as for :func:`load`."""
    try:
        return elaborate(spec, sources[path], sources, synthesis)
    except RecursionError:
        # the tree walks are recursive; absurdly deep nesting is bad input, not a crash
        return None, [too_deep(path)]


def not_text(path: str, where: tuple[int, int]) -> Diagnostic:
    """E0008: the input is binary (checked on its first bytes, before any parsing), located
    at its first NUL or control byte."""
    return error("E0008", f"{path} is not a text file (it contains NUL or control bytes); "
                 "iterc reads FSP specs (.lts text files)", Span(path, *where))
