"""The MTSA conformance corpus runner (``iterc conformance``).

The corpus (``../shared/conformance/mtsa``) is a folder of FSP files from MTSA's own test suite and
a ``verdicts.tsv`` that says what MTSA's tests expect of each file.  This module turns one TSV row
into one :class:`RowResult` and runs the whole table, each row in its own Python process so that a
crash, a blow-up or a time-out in one file never takes the report down.

Contract of a row check (:func:`check_row`): it never raises; every outcome is a status

* ``pass`` — the verdict (and the checks we implement) match;
* ``fail`` — a verdict or check disagrees with MTSA's expectation;
* ``unsupported`` — the front-end rejected a construct with an "unsupported construct"
  diagnostic (counted separately, as the corpus README asks);
* ``error`` — the file produced error diagnostics where MTSA compiles it;
* ``crash`` — an exception escaped the compiler (a bug);
* ``timeout`` — the row exceeded its time limit (set by the driver).

A *baseline* file (``tests/data/conformance_baseline.tsv``: ``file<TAB>status``) records what
passed when it was written; the command exits 1 if a row that passed there no longer passes, so
the corpus acts as a ratchet in CI while unsupported corners are still being filled in.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import time
import traceback
from collections import Counter
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path

STATUSES = ("pass", "fail", "unsupported", "error", "crash", "timeout")


@dataclass(frozen=True, slots=True)
class Row:
    """One line of ``verdicts.tsv``."""

    file: str
    expected: str
    composite: str
    keywords: str
    checks: str

    @property
    def composite_name(self) -> str:
        """The composite to build: the first word (``B (fallback: ...)`` → ``B``)."""
        name = self.composite.split()[0] if self.composite.strip() else "C"
        return name.split("(")[0] or "DEFAULT"

    @property
    def kind(self) -> str:
        """The verdict family: realizable, unrealizable, compiles, alphabet, recursion,
        bisimilar, legal, not legal."""
        e = self.expected
        if e.startswith("unrealizable"):
            return "unrealizable"
        if e.startswith("realizable"):
            return "realizable"
        if e.startswith("compiles"):
            return "compiles"
        if e.startswith("alphabet"):
            return "alphabet"
        if e.startswith("error: recursive"):
            return "recursion"
        if e.startswith("n.a.") and "bisimulation" in self.checks:
            return "bisimilar"
        if e.startswith("not legal"):
            return "not legal"
        if e.startswith("legal"):
            return "legal"
        return "other"


@dataclass(frozen=True, slots=True)
class RowResult:
    """The outcome of one row: status, a one-line detail, and the wall time in seconds."""

    file: str
    kind: str
    status: str
    detail: str
    seconds: float


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


def _is_unsupported(diag) -> bool:
    return "unsupported" in diag.message.lower() or diag.code.startswith("U")


def _first_errors(diags, limit: int = 1) -> str:
    from iterplan_compiler.diagnostics import Severity

    errs = [d for d in diags if d.severity == Severity.ERROR]
    parts = []
    for d in errs[:limit]:
        parts.append(f"{d.span.line}:{d.span.column}: [{d.code}] {d.message}")
    return "; ".join(parts)


def _expected_alphabet(checks: str) -> set[str] | None:
    start, end = checks.find("["), checks.find("]")
    if start < 0 or end < start:
        return None
    return set(checks[start + 1:end].split())


def check_row(root: Path, row: Row) -> RowResult:
    """Check one row in this process; never raises (see the module docstring)."""
    start = time.perf_counter()
    try:
        status, detail = _check(root, row)
    except Exception as exc:  # a compiler bug: report it, keep the traceback's last frame
        tb = traceback.extract_tb(exc.__traceback__)
        where = f" at {Path(tb[-1].filename).name}:{tb[-1].lineno}" if tb else ""
        status, detail = "crash", f"{type(exc).__name__}: {exc}{where}"
    detail = detail.strip().splitlines()[0] if detail.strip() else ""
    return RowResult(row.file, row.kind, status, detail, time.perf_counter() - start)


def _check(root: Path, row: Row) -> tuple[str, str]:
    from iterplan_compiler import frontend
    from iterplan_compiler.diagnostics import has_errors

    model, diags = frontend.load(root / row.file)
    kind = row.kind
    if kind == "recursion":
        msgs = " ".join(d.message.lower() for d in diags)
        if model is not None:
            _, more = model.build_lts(row.composite_name)
            msgs += " " + " ".join(d.message.lower() for d in more)
        if "recursive" in msgs:
            return "pass", "recursive composition reported"
        return "fail", "no recursive-composition error"
    if model is None or has_errors(diags):
        if any(_is_unsupported(d) for d in diags):
            return "unsupported", _first_errors([d for d in diags if _is_unsupported(d)])
        if row.expected.startswith("compiles (errors only printed"):
            return "pass", "errors printed (MTSA's test never fails)"
        return "error", _first_errors(diags)
    name = row.composite_name
    if kind in ("realizable", "unrealizable"):
        return _check_synthesis(model, row)
    if kind == "compiles":
        return _check_compiles(model, row)
    if kind == "alphabet":
        # MTSA's composition of an unrealizable controller composite is the plant `C_#NC#`
        # (semantics notes §3.7); its alphabet is what the test compares.
        lts, more = model.build_lts(name, unrealizable="plant")
    else:
        lts, more = model.build_lts(name)
    if lts is None or has_errors(more):
        if any(_is_unsupported(d) for d in more):
            return "unsupported", _first_errors([d for d in more if _is_unsupported(d)])
        return "error", f"building {name}: {_first_errors(more)}"
    if kind == "alphabet":
        expected = _expected_alphabet(row.checks) or set()
        got = set(lts.alphabet)
        if got == expected:
            return "pass", f"alphabet {sorted(got)}"
        return "fail", f"alphabet {sorted(got)}, expected {sorted(expected)}"
    if kind == "bisimilar":
        from iterplan_compiler.ir.minimise import bisimilar

        exp, more2 = model.build_lts("ExpectedC")
        if exp is None:
            return "error", f"building ExpectedC: {_first_errors(more2)}"
        ok = bisimilar(lts, exp)
        return ("pass" if ok else "fail"), (
            f"{lts.num_states} states vs ExpectedC {exp.num_states}: "
            + ("bisimilar" if ok else "not bisimilar"))
    if kind in ("legal", "not legal"):
        return _check_legality(model, row)
    return "pass", "compiles"


def _check_compiles(model, row: Row) -> tuple[str, str]:
    from iterplan_compiler.diagnostics import has_errors

    names = [row.composite_name] if row.composite_name in model.names() else []
    if not names:
        return "pass", "compiles (no such composite; MTSA falls back)"
    lts, more = model.build_lts(names[0])
    if lts is not None and not has_errors(more):
        return "pass", f"{names[0]}: {lts.num_states} states"
    if any(_is_unsupported(d) for d in more):
        return "unsupported", _first_errors([d for d in more if _is_unsupported(d)])
    # `controller` composites that are unrealizable still "compile" in MTSA (C_#NC#).
    if any("unrealizable" in d.message.lower() or "no controller" in d.message.lower()
           for d in more):
        return "pass", f"{names[0]}: compiles (unrealizable)"
    return "error", f"building {names[0]}: {_first_errors(more)}"


def _check_synthesis(model, row: Row) -> tuple[str, str]:
    """Verdict plus the row's checks, by :func:`iterplan_compiler.synthesis.conformance.check_row`
    (``None`` there means the row needs an unsupported feature)."""
    from iterplan_compiler.synthesis.conformance import check_row as check_synthesis_row

    ok, detail = check_synthesis_row(model, row)
    if ok is None:
        return "unsupported", detail
    return ("pass" if ok else "fail"), detail


def _check_legality(model, row: Row) -> tuple[str, str]:
    """MTSA's LegalityAnalyser verdict for the row's composite (``Model.legality``)."""
    legal, detail = model.legality(row.composite_name)
    want = row.kind == "legal"
    return ("pass" if legal == want else "fail"), detail


# --------------------------------------------------------------------------------------------
# The whole table, one process per row


def _run_isolated(root: Path, row: Row, timeout: float) -> RowResult:
    cmd = [sys.executable, "-m", "iterplan_compiler.conformance", "--one", str(root), row.file]
    start = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                              env={**os.environ, "PYTHONHASHSEED": "0"})
    except subprocess.TimeoutExpired:
        return RowResult(row.file, row.kind, "timeout", f"> {timeout:g} s", timeout)
    elapsed = time.perf_counter() - start
    for line in reversed(proc.stdout.splitlines()):
        if line.startswith("{"):
            try:
                data = json.loads(line)
                return RowResult(**data)
            except (ValueError, TypeError):
                break
    tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
    return RowResult(row.file, row.kind, "crash", f"exit {proc.returncode}: {tail}", elapsed)


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
        from iterplan_compiler import frontend

        frontend.load(root / "warm-up.lts", text="A = (a -> A).\n")
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
    from multiprocessing.connection import wait

    rows = list(rows)
    if "fork" not in mp.get_all_start_methods():
        return _run_spawned(root, rows, jobs=jobs, timeout=timeout, budget=budget,
                            on_result=on_result)
    _warm_up(root)
    ctx = mp.get_context("fork")
    results: list[RowResult | None] = [None] * len(rows)
    deadline = None if budget is None else time.monotonic() + budget
    pending = list(range(len(rows)))
    running: dict[object, tuple[int, object, float]] = {}  # conn -> (index, process, start)

    def finish(i: int, res: RowResult) -> None:
        results[i] = res
        if on_result is not None:
            on_result(res)

    while pending or running:
        while pending and len(running) < max(1, jobs):
            i = pending.pop(0)
            row = rows[i]
            if deadline is not None and time.monotonic() > deadline:
                finish(i, RowResult(row.file, row.kind, "timeout", "budget exhausted", 0.0))
                continue
            recv, send = ctx.Pipe(duplex=False)
            proc = ctx.Process(target=_child, args=(send, root, row), daemon=True)
            proc.start()
            send.close()
            running[recv] = (i, proc, time.monotonic())
        if not running:
            continue
        now = time.monotonic()
        next_expiry = min(start + timeout for _, _, start in running.values())
        ready = wait(list(running), timeout=max(0.0, next_expiry - now))
        for conn in ready:
            i, proc, start = running.pop(conn)
            row = rows[i]
            try:
                data = conn.recv()
                res = RowResult(**data)
            except (EOFError, OSError, TypeError):
                proc.join(5)
                res = RowResult(row.file, row.kind, "crash",
                                f"worker died (exit {proc.exitcode})",
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
                finish(i, RowResult(row.file, row.kind, "timeout", f"> {timeout:g} s", timeout))
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
            return RowResult(row.file, row.kind, "timeout", "budget exhausted", 0.0)
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
    """``file -> status`` from a baseline TSV (missing file → empty)."""
    if not path.exists():
        return {}
    out = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        if line and not line.startswith("#"):
            file, _, status = line.partition("\t")
            out[file] = status.strip()
    return out


def write_baseline(path: Path, results: Iterable[RowResult]) -> None:
    """Write ``file<TAB>status`` lines, sorted by file, for the ratchet."""
    lines = ["# iterc conformance baseline: rows listed as pass must keep passing"]
    lines += [f"{r.file}\t{r.status}" for r in sorted(results, key=lambda r: r.file)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def regressions(results: Iterable[RowResult], baseline: dict[str, str]) -> list[RowResult]:
    """Rows that passed in the baseline and do not pass now."""
    return [r for r in results if baseline.get(r.file) == "pass" and r.status != "pass"]


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
    """``python -m iterplan_compiler.conformance --one ROOT FILE``: check one row, print JSON."""
    root, file = Path(argv[0]), argv[1]
    rows = [r for r in read_rows(root) if r.file == file]
    if not rows:
        print(json.dumps(asdict(RowResult(file, "other", "error", "not in verdicts.tsv", 0.0))))
        return 0
    print(json.dumps(asdict(check_row(root, rows[0]))))
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--one", nargs=2)
    ns = parser.parse_args()
    sys.exit(_main_one(ns.one))
