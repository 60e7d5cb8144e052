"""MTSA conformance: every realizable/unrealizable row of ``verdicts.tsv`` (§4.2).

Checks the verdict, ``ExpectedC`` bisimilarity (BisimilarFSP) and the rows' ``assert`` checks on
the controlled system (see :mod:`iterplan_compiler.synthesis.conformance`).  Skipped when the
shared corpus is absent.
"""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3] / "shared" / "conformance" / "mtsa"
if not (ROOT / "verdicts.tsv").is_file():
    ROOT = Path("/work/shared/conformance/mtsa")


def _rows():
    if not (ROOT / "verdicts.tsv").is_file():
        return []
    from iterplan_compiler.conformance import read_rows

    return [r for r in read_rows(ROOT) if r.kind in ("realizable", "unrealizable")]


ROWS = _rows()


@pytest.mark.skipif(not ROWS, reason="shared conformance corpus (../shared) not present")
@pytest.mark.parametrize("row", ROWS, ids=[f"{r.file}:{r.composite_name}" for r in ROWS])
def test_synthesis_row(row):
    from iterplan_compiler.frontend import load
    from iterplan_compiler.synthesis.conformance import check_row

    model, diags = load(str(ROOT / row.file))
    assert model is not None, [d.message for d in diags]
    ok, detail = check_row(model, row)
    assert ok is True, f"{row.file} [{row.composite_name}] expected {row.expected}: {detail}"
