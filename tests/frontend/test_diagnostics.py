"""Diagnostics suite: each ``tests/data/diagnostics/*.lts`` file marks the expected diagnostics
on the offending line with a comment ``// error: CODE`` (or ``// warning: CODE``).

The runner loads the file (and builds every machine, so build-time errors count) and checks
that the set of (line, severity, code) of the reported diagnostics equals the marked set.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from iterplan_compiler.frontend import load

DATA = Path(__file__).resolve().parents[1] / "data" / "diagnostics"
MARK = re.compile(r"//\s*(error|warning):\s*([A-Z]\d{4})")


def _expected(text: str) -> set[tuple[int, str, str]]:
    out = set()
    for i, line in enumerate(text.splitlines(), start=1):
        for sev, code in MARK.findall(line):
            out.add((i, sev, code))
    return out


@pytest.mark.parametrize("path", sorted(DATA.glob("*.lts")), ids=lambda p: p.name)
def test_diagnostics_file(path: Path):
    text = path.read_text(encoding="utf-8")
    model, diags = load(str(path), text)
    if model is not None:
        for name in model.names():
            _, ds = model.build_lts(name)
            diags += [d for d in ds if d not in diags]
    got = {(d.span.line, d.severity.value, d.code) for d in diags
           if d.span.file == str(path)}
    assert got == _expected(text), "\n".join(d.message for d in diags)
