"""Spec -> generated controller module, for the demo, the experiments and the example tests.

Runs :func:`iterplan_compiler.pipeline.compile_spec` (every pass); a spec with errors, or a bug
in a pass, comes back as a readable message (:class:`StageError`), never as a traceback.
"""

from __future__ import annotations

import importlib.util
import sys
from collections.abc import Iterable, Mapping
from pathlib import Path
from types import ModuleType

from iterplan_compiler.diagnostics import Diagnostic, render
from iterplan_compiler.experiments.catalog import EXAMPLES, example_path
from iterplan_compiler.pipeline import compile_spec


class StageError(RuntimeError):
    """A pipeline stage reported errors or failed; ``stage`` names it, the message says what
    to do."""

    def __init__(self, stage: str, message: str):
        self.stage = stage
        super().__init__(f"{stage}: {message}")


def _render(diags: Iterable[Diagnostic], sources: Mapping[str, str]) -> str:
    return render(list(diags), dict(sources))


def compile_to_source(spec: Path, composite: str | None = None,
                      text: str | None = None) -> tuple[str, dict]:
    """Run front-end, synthesis and the Python back-end; return (module source, stats)."""
    try:
        out = compile_spec(spec, composite=composite, text=text)
    except Exception as exc:  # a bug in another stage: report it, do not crash the caller
        raise StageError("compile", f"internal error while compiling {spec.name}: "
                         f"{type(exc).__name__}: {exc}") from None
    if out.text is None:
        raise StageError("compile", "the spec did not compile:\n" +
                         _render(out.diagnostics, out.sources))
    return out.text, dict(out.stats)


def import_module_file(path: Path, name: str) -> ModuleType:
    """Import a generated controller module from ``path`` under module name ``name``."""
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise StageError("import", f"cannot import {path}")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


def compile_example(name: str, out_dir: Path, *, text: str | None = None,
                    reuse: bool = False) -> tuple[Path, dict]:
    """Compile bundled example ``name`` into ``out_dir/<name>_controller.py``.

    With ``reuse``, an existing module generated from the same spec text (its header records
    the spec's sha256) is kept; by default the module is regenerated, so a changed compiler
    never leaves a stale controller behind.
    """
    ex = EXAMPLES[name]
    spec = example_path(name)
    src_text = text if text is not None else spec.read_text()
    out_dir.mkdir(parents=True, exist_ok=True)
    target = out_dir / f"{name}_controller.py"
    from hashlib import sha256

    digest = sha256(src_text.encode("utf-8")).hexdigest()
    if reuse and target.exists() and digest in target.read_text():
        return target, {"cached": True}
    source, stats = compile_to_source(spec, ex.composite, text=src_text)
    from iterplan_compiler.outputs import atomic_write_text

    atomic_write_text(target, source)
    return target, stats
