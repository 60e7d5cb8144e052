"""MTSA conformance: every realizable/unrealizable row of ``verdicts.tsv`` (§4.2).

Every check the row names (verdict, ``ntransitions>0``, ``assert``s on the named systems,
legality, ``ExpectedC`` bisimilarity; see :mod:`iterplan_compiler.conformance_checks`) must
pass.  Skipped when the shared corpus is absent.
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
@pytest.mark.parametrize("row", ROWS, ids=[r.key for r in ROWS])
def test_synthesis_row(row):
    from iterplan_compiler.conformance import check_row

    res = check_row(ROOT, row)
    assert res.checks and res.status == "pass", f"{row.key} expected {row.expected}: {res.detail}"
