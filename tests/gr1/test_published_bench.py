"""``benchmarks/gr1/published.py``: finds ``synt15_<n>.txt`` files and tabulates the runs.

The published instance files are not shipped, so the end-to-end check runs the script on a
file of our own ``synt15`` family saved under the published naming scheme.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks" / "gr1"))

import generators  # noqa: E402
import published  # noqa: E402


def test_instances_by_name(tmp_path: Path) -> None:
    for name in ("synt15_13.txt", "synt15_2.slugsin", "synt15_x.txt", "jcss12_4.txt",
                 "synt15_40.txt.bak"):
        (tmp_path / name).write_text("")
    assert [(n, p.name) for n, p in published.instances(tmp_path)] == [
        (2, "synt15_2.slugsin"), (13, "synt15_13.txt")]


def test_row_medians_and_timeouts() -> None:
    runs = [{"status": "ok", "realizable": True, "total_cpu_s": c, "reordering_s": 0.5,
             "reorderings": 4, "trigger_raises": t, "peak_live_nodes": 100}
            for c, t in ((3.0, 2), (1.0, 2), (2.0, 3))]
    row = published.row(60, runs)
    assert row.startswith("| 60 | REALIZABLE | 2.00 (1.00–3.00) | 0.50 | 4 | 2 | 100 |")
    assert "gr1c 42.11" in row
    assert published.row(7, [{"status": "timeout"}]).startswith("| 7 | timeout | - |")


def test_end_to_end_on_our_encoding(tmp_path: Path) -> None:
    (tmp_path / "synt15_2.txt").write_text(generators.FAMILIES["synt15"](2), encoding="utf-8")
    proc = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "gr1" / "published.py"), str(tmp_path),
         "--runs", "1", "--limit", "120"],
        capture_output=True, text=True, timeout=180, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    rows = [line for line in proc.stdout.splitlines() if line.startswith("| 2 |")]
    assert len(rows) == 1 and "| REALIZABLE |" in rows[0], proc.stdout
