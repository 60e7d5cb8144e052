"""The MTSA conformance corpus runner (``iterc conformance``).

The corpus (``../shared/conformance/mtsa``) is a folder of FSP files from MTSA's own test suite and
a ``verdicts.tsv`` that says what MTSA's tests expect of each file.  This module turns one TSV row
into one :class:`RowResult` and runs the whole table, each row in its own Python process so that a
crash, a blow-up or a time-out in one file never takes the report down.

A row's checks are planned and run by :mod:`iterplan_compiler.conformance_checks`: the verdict
of its family and every clause of its ``checks`` column, each with its own status; the row's
status is the worst of them (``pass`` < ``unsupported`` < ``fail`` < ``error`` < ``crash`` <
``timeout``).  An unknown verdict family or an unrecognised clause is an ``error`` check.
:func:`check_row` never raises.

A *baseline* file (``tests/data/conformance_baseline.tsv``: ``key<TAB>status``, the key being
``file::composite`` so rows sharing a file stay apart) records what passed; the command exits 1
if a row that passed there no longer passes, and rewriting the baseline never drops a pass.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import re
import subprocess
import sys
import time
import traceback
from collections import Counter
from collections.abc import Callable, Iterable, Mapping
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from iterplan_compiler import conformance_checks as cc
from iterplan_compiler.conformance_checks import CheckResult, Family, Status

STATUSES = cc.STATUSES
_PARENS = re.compile(r"\([^)]*\)")


@dataclass(frozen=True, slots=True)
class Row:
    """One line of ``verdicts.tsv``."""

    file: str
    expected: str
    composite: str
    keywords: str
    checks: str

    @property
    def composites(self) -> tuple[str, ...]:
        """Every composite the column lists: ``TT, BIS, C, Comp`` -> four names,
        ``B (fallback: ...)`` -> ``B`` (the one MTSA built), ``DEFAULT(all processes)`` ->
        ``DEFAULT``; an empty cell -> ``C``."""
        names = [n.strip() for n in _PARENS.sub("", self.composite).split(",")]
        return tuple(n for n in names if n) or ("C",)

    @property
    def key(self) -> str:
        """The row's identity in the baseline: ``file::first composite``."""
        return f"{self.file}::{self.composites[0]}"

    @property
    def family(self) -> Family:
        return cc.family(self.expected)

    @property
    def kind(self) -> str:
        """The verdict family's name (the report's first column)."""
        return self.family.value


@dataclass(frozen=True, slots=True)
class RowResult:
    """The outcome of one row: status (the worst of its checks), the checks, wall seconds."""

    file: str
    key: str
    kind: str
    status: str
    detail: str
    seconds: float
    checks: tuple[CheckResult, ...] = ()

    @staticmethod
    def from_dict(data: Mapping[str, Any]) -> RowResult:
        checks = tuple(CheckResult(c["name"], Status(c["status"]), c["detail"])
                       for c in data.get("checks", ()))
        return RowResult(data["file"], data["key"], data["kind"], data["status"],
                         data["detail"], float(data["seconds"]), checks)

    @staticmethod
    def whole(row: Row, status: Status, detail: str, seconds: float) -> RowResult:
        """A result decided for the row as a whole (time-out, crash of the worker)."""
        return RowResult(row.file, row.key, row.kind, status.value, detail, seconds)


def read_rows(root: Path) -> list[Row]:
    """Read ``root/verdicts.tsv`` (the header row is skipped)."""
    with open(root / "verdicts.tsv", newline="", encoding="utf-8") as fh:
        reader = csv.reader(fh, delimiter="\t")
        header = next(reader, None)
        rows = []
        for rec in reader:
            if not rec or rec == header:
                continue
            rec = (rec + [""] * 5)[:5]
            rows.append(Row(*rec))
    return rows


# --------------------------------------------------------------------------------------------
# One row, in-process


def check_row(root: Path, row: Row) -> RowResult:
    """Check one row in this process; never raises (see the module docstring)."""
    start = time.perf_counter()
    try:
        results = _check(root, row)
    except Exception as exc:  # a compiler bug: report it, keep the traceback's last frame
        tb = traceback.extract_tb(exc.__traceback__)
        where = f" at {Path(tb[-1].filename).name}:{tb[-1].lineno}" if tb else ""
        results = [CheckResult("row", Status.CRASH, f"{type(exc).__name__}: {exc}{where}")]
    status = cc.worst([r.status for r in results])
    detail = "; ".join(" ".join(r.line().split()) for r in results)
    return RowResult(row.file, row.key, row.kind, status.value, detail,
                     time.perf_counter() - start, tuple(results))


def _check(root: Path, row: Row) -> list[CheckResult]:
    from iterplan_compiler import pipeline

    model, diags = pipeline.load_model(root / row.file)
    problem = cc.diag_status(diags)
    if model is None or problem is not None:
        return [_load_failure(row, diags, problem or Status.ERROR)]
    return cc.run_checks(model, cc.plan(row.expected, row.composites, row.checks))


def _load_failure(row: Row, diags: list, status: Status) -> CheckResult:
    """The file does not load: only a recursion row (E0401 expected) or MTSA's never-failing
    parser tests can still pass."""
    found = cc.first_error(diags)
    if row.family == Family.RECURSION:
        ok = any(d.code == cc.RECURSION_CODE for d in cc.errors_of(diags))
        return CheckResult("recursive composition", Status.PASS if ok else Status.FAIL, found)
    if row.family == Family.NEVER_FAILS and status != Status.UNSUPPORTED:
        return CheckResult("loads (MTSA only prints errors)", Status.PASS, found)
    return CheckResult("loads", status, found)


# --------------------------------------------------------------------------------------------
# The whole table, one process per row


def _run_isolated(root: Path, row: Row, timeout: float) -> RowResult:
    cmd = [sys.executable, "-m", "iterplan_compiler.conformance", "--one", str(root), row.key]
    start = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                              env={**os.environ, "PYTHONHASHSEED": "0"})
    except subprocess.TimeoutExpired:
        return RowResult.whole(row, Status.TIMEOUT, f"> {timeout:g} s", timeout)
    elapsed = time.perf_counter() - start
    for line in reversed(proc.stdout.splitlines()):
        if line.startswith("{"):
            try:
                data = json.loads(line)
                return RowResult.from_dict(data)
            except (ValueError, TypeError):
                break
    tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
    return RowResult.whole(row, Status.CRASH, f"exit {proc.returncode}: {tail}", elapsed)


def _warm_up(root: Path) -> None:
    """Import the pipeline and build the parser once, before forking row workers.

    Forked children inherit the warm interpreter, so a row costs its own work only, not
    seconds of imports and LALR table construction.
    """
    import importlib

    for mod in ("iterplan_compiler.frontend", "iterplan_compiler.synthesis.driver",
                "iterplan_compiler.fltl.check", "iterplan_compiler.ir.minimise"):
        try:
            importlib.import_module(mod)
        except ImportError:
            pass
    try:
        from iterplan_compiler import pipeline

        pipeline.load_model(root / "warm-up.lts", text="A = (a -> A).\n")
    except Exception:  # warming up is an optimisation only
        pass


def _child(conn, root: Path, row: Row) -> None:
    res = check_row(root, row)
    conn.send(asdict(res))
    conn.close()


def run_corpus(root: Path, rows: Iterable[Row], *, jobs: int, timeout: float,
               budget: float | None = None,
               on_result: Callable[[RowResult], None] | None = None) -> list[RowResult]:
    """Check every row, ``jobs`` at a time, each in a child process; call ``on_result`` as
    each finishes.

    Children are forked from a warmed-up parent where ``fork`` exists (else spawned fresh
    interpreters run ``--one``).  A child that exceeds ``timeout`` is killed (``timeout``); one
    that dies without a result is a ``crash``.  ``budget`` bounds the whole run in wall
    seconds: a row not started when it is spent is reported as ``timeout`` ("budget
    exhausted").  Results come back in the order of ``rows`` (put the rows that matter most
    first).
    """
    import multiprocessing as mp
    from multiprocessing.connection import Connection, wait
    from multiprocessing.process import BaseProcess

    rows = list(rows)
    if "fork" not in mp.get_all_start_methods():
        return _run_spawned(root, rows, jobs=jobs, timeout=timeout, budget=budget,
                            on_result=on_result)
    _warm_up(root)
    ctx = mp.get_context("fork")
    results: list[RowResult | None] = [None] * len(rows)
    deadline = None if budget is None else time.monotonic() + budget
    pending = list(range(len(rows)))
    running: dict[Connection, tuple[int, BaseProcess, float]] = {}  # conn -> (index, process, start)

    def finish(i: int, res: RowResult) -> None:
        results[i] = res
        if on_result is not None:
            on_result(res)

    while pending or running:
        while pending and len(running) < max(1, jobs):
            i = pending.pop(0)
            row = rows[i]
            if deadline is not None and time.monotonic() > deadline:
                finish(i, RowResult.whole(row, Status.TIMEOUT, "budget exhausted", 0.0))
                continue
            recv, send = ctx.Pipe(duplex=False)
            proc: BaseProcess = ctx.Process(target=_child, args=(send, root, row), daemon=True)
            proc.start()
            send.close()
            running[recv] = (i, proc, time.monotonic())
        if not running:
            continue
        now = time.monotonic()
        next_expiry = min(start + timeout for _, _, start in running.values())
        ready = wait(list(running), timeout=max(0.0, next_expiry - now))
        for conn in ready:
            assert isinstance(conn, Connection)
            i, proc, start = running.pop(conn)
            row = rows[i]
            try:
                data = conn.recv()
                res = RowResult.from_dict(data)
            except (EOFError, OSError, TypeError):
                proc.join(5)
                res = RowResult.whole(row, Status.CRASH, f"worker died (exit {proc.exitcode})",
                                      time.monotonic() - start)
            conn.close()
            proc.join(5)
            finish(i, res)
        now = time.monotonic()
        for conn, (i, proc, start) in list(running.items()):
            if now - start >= timeout:
                proc.kill()
                proc.join(5)
                conn.close()
                del running[conn]
                row = rows[i]
                finish(i, RowResult.whole(row, Status.TIMEOUT, f"> {timeout:g} s", timeout))
    return [r for r in results if r is not None]


def _run_spawned(root: Path, rows: list[Row], *, jobs: int, timeout: float,
                 budget: float | None,
                 on_result: Callable[[RowResult], None] | None) -> list[RowResult]:
    """Fallback without ``fork``: one fresh interpreter per row (slower start-up)."""
    from concurrent.futures import as_completed

    results: list[RowResult | None] = [None] * len(rows)
    deadline = None if budget is None else time.monotonic() + budget

    def work(row: Row) -> RowResult:
        if deadline is not None and time.monotonic() > deadline:
            return RowResult.whole(row, Status.TIMEOUT, "budget exhausted", 0.0)
        return _run_isolated(root, row, timeout)

    with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        futures = {pool.submit(work, row): i for i, row in enumerate(rows)}
        for fut in as_completed(futures):
            res = fut.result()
            results[futures[fut]] = res
            if on_result is not None:
                on_result(res)
    return [r for r in results if r is not None]


def read_baseline(path: Path) -> dict[str, str]:
    """``key -> status`` from a baseline TSV (missing file -> empty).  A line of the old format
    (``file<TAB>status``, no ``::``) stands for every row of that file (see
    :func:`baseline_status`)."""
    if not path.exists():
        return {}
    out: dict[str, str] = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        if line and not line.startswith("#"):
            key, _, status = line.partition("\t")
            old = out.get(key)
            # an old-format file listed twice (two rows): it passed only if both did
            out[key] = status.strip() if old in (None, status.strip()) else "fail"
    return out


def baseline_status(baseline: Mapping[str, str], key: str) -> str | None:
    """A row's status in ``baseline``: by its key, else by its file (old format)."""
    if key in baseline:
        return baseline[key]
    return baseline.get(key.partition("::")[0])


def write_baseline(path: Path, results: Iterable[RowResult],
                   keep: Mapping[str, str] | None = None) -> None:
    """Write ``key<TAB>status`` lines, sorted by key, for the ratchet.  A row that passed in
    ``keep`` (the previous baseline) stays ``pass``: the ratchet never loses a row, a row
    that stopped passing shows up as a regression until the code is fixed."""
    keep = keep or {}
    lines = ["# iterc conformance baseline (key = file::composite): rows listed as pass must "
             "keep passing"]
    for r in sorted(results, key=lambda r: r.key):
        status = "pass" if baseline_status(keep, r.key) == "pass" else r.status
        lines.append(f"{r.key}\t{status}")
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text("\n".join(lines) + "\n", encoding="utf-8")
    os.replace(tmp, path)


def regressions(results: Iterable[RowResult], baseline: Mapping[str, str]) -> list[RowResult]:
    """Rows that passed in the baseline and do not pass now."""
    return [r for r in results
            if baseline_status(baseline, r.key) == "pass" and r.status != "pass"]


def summary_table(results: list[RowResult]) -> str:
    """A per-verdict-family table of status counts, plus totals and time."""
    kinds = sorted({r.kind for r in results})
    width = max([len(k) for k in kinds] + [8])
    head = f"{'verdict':<{width}}  " + "  ".join(f"{s:>11}" for s in STATUSES) + "  total"
    lines = [head, "-" * len(head)]
    for kind in kinds + ["all"]:
        sel = [r for r in results if kind in ("all", r.kind)]
        counts = Counter(r.status for r in sel)
        lines.append(f"{kind:<{width}}  " + "  ".join(f"{counts[s]:>11}" for s in STATUSES)
                     + f"  {len(sel):>5}")
    total = sum(r.seconds for r in results)
    slowest = sorted(results, key=lambda r: -r.seconds)[:3]
    lines.append(f"time: {total:.1f} s in all, mean {total / max(1, len(results)):.2f} s/file; "
                 "slowest: " + ", ".join(f"{r.file} {r.seconds:.1f} s" for r in slowest))
    return "\n".join(lines)


def _main_one(argv: list[str]) -> int:
    """``python -m iterplan_compiler.conformance --one ROOT KEY``: check one row, print JSON."""
    root, key = Path(argv[0]), argv[1]
    rows = [r for r in read_rows(root) if r.key == key]
    if not rows:
        res = RowResult(key.partition("::")[0], key, Family.UNKNOWN.value, "error",
                        "not in verdicts.tsv", 0.0)
        print(json.dumps(asdict(res)))
        return 0
    print(json.dumps(asdict(check_row(root, rows[0]))))
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--one", nargs=2)
    ns = parser.parse_args()
    sys.exit(_main_one(ns.one))
