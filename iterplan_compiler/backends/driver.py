"""Former home of the compile pipeline, now :mod:`iterplan_compiler.pipeline` (the passes) and
:mod:`iterplan_compiler.backends.output` (the emit stage).

Kept only so that ``experiments/pipeline.py`` (owned elsewhere) keeps working until it imports
``compile_spec`` from :mod:`iterplan_compiler.pipeline`; nothing in the compiler imports this.
"""

from __future__ import annotations

from iterplan_compiler.backends.output import EMIT_KINDS, EmitKind
from iterplan_compiler.pipeline import CompileOutput, compile_spec

__all__ = ["EMIT_KINDS", "CompileOutput", "EmitKind", "compile_spec"]
