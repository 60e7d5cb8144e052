"""Synthesis time: iterator-based examples vs the explicit-location Fire Patrol, growing N.

For the iterator-based specs N (the number of locations) does not occur in the spec at all, so
each is synthesised once and its time holds for every N.  The explicit version names its N
patrol locations and must remember which were patrolled in the current round, so its game
grows as 2^N.  Ordered Patrol is the paper's exception: its N ordered locations *are* in the
spec (one sensor each), and it grows with N as well.

Every synthesis runs in a child process with a time budget, so an exploding case is cut off
and reported as "> budget" instead of hanging the table.
"""

from __future__ import annotations

import multiprocessing as mp
import time
from dataclasses import dataclass
from pathlib import Path

from iterplan_compiler.experiments.catalog import (
    EXAMPLES,
    example_path,
    explicit_fire_patrol,
    with_constant,
)


@dataclass(frozen=True)
class Row:
    """One synthesis measurement.  ``status``: realizable / unrealizable / timeout / error."""

    spec: str
    n: int | None
    status: str
    load_s: float
    synth_s: float
    states: int | None
    detail: str = ""


def synthesise_text(path: Path, text: str, composite: str) -> dict:
    """Front-end + synthesis of ``composite`` in ``text`` (``path`` anchors includes).

    Returns a dict with status, times and the controller/game sizes; never raises for bad
    input (errors come back as ``status="error"``)."""
    try:
        from iterplan_compiler.frontend import load
        from iterplan_compiler.synthesis.driver import synthesize
    except ImportError as exc:
        return {"status": "error", "detail": f"pipeline stage missing: {exc}"}
    t0 = time.perf_counter()
    model, diags = load(str(path), text)
    if model is None:
        return {"status": "error", "detail": _first_error(diags)}
    problem, diags2 = model.synthesis_problem(composite)
    t1 = time.perf_counter()
    if problem is None:
        return {"status": "error", "detail": _first_error(diags2), "load_s": t1 - t0}
    result = synthesize(problem)
    t2 = time.perf_counter()
    stats = dict(getattr(result, "stats", {}) or {})
    states = None
    for key in ("game_states", "plant_states", "states", "composition_states"):
        if isinstance(stats.get(key), int):
            states = stats[key]
            break
    comp = getattr(result, "composition", None)
    if states is None and comp is not None:
        states = comp.num_states
    return {"status": "realizable" if result.realizable else "unrealizable",
            "load_s": t1 - t0, "synth_s": t2 - t1, "states": states,
            "detail": "" if result.realizable else str(result.explanation)[:200]}


def _first_error(diags) -> str:
    for d in diags:
        if str(getattr(d, "severity", "")).lower().endswith("error"):
            return f"{d.code}: {d.message}"
    return "front-end failed"


def _child(q, path, text, composite):  # pragma: no cover - runs in a subprocess
    try:
        q.put(synthesise_text(Path(path), text, composite))
    except Exception as exc:
        q.put({"status": "error", "detail": f"{type(exc).__name__}: {exc}"})


def measure(spec: str, n: int | None, path: Path, text: str, composite: str,
            budget_s: float) -> Row:
    """Synthesise in a child process, killed after ``budget_s`` seconds."""
    ctx = mp.get_context("fork") if hasattr(mp, "get_context") else mp
    q = ctx.Queue()
    proc = ctx.Process(target=_child, args=(q, str(path), text, composite), daemon=True)
    t0 = time.perf_counter()
    proc.start()
    res = None
    try:
        res = q.get(timeout=budget_s)
    except Exception:
        res = None
    finally:
        if proc.is_alive():
            proc.terminate()
        proc.join(5)
    if res is None:
        return Row(spec, n, "timeout", float("nan"), time.perf_counter() - t0, None,
                   f"> {budget_s:g} s")
    return Row(spec, n, res.get("status", "error"), float(res.get("load_s", float("nan"))),
               float(res.get("synth_s", float("nan"))), res.get("states"),
               res.get("detail", ""))


def table(ns: list[int], *, budget_s: float = 60.0, progress=None) -> list[Row]:
    """All rows: each iterator-based example once, then the explicit Fire Patrol and the
    Ordered Patrol for each N (stopping a series after its first timeout)."""
    rows: list[Row] = []
    _warm_up()
    for ex in EXAMPLES.values():
        if not ex.iterator or ex.name == "ordered_patrol":
            continue
        p = example_path(ex.name)
        rows.append(measure(ex.name, None, p, p.read_text(), ex.composite, budget_s))
        if progress:
            progress.update(rows[-1].status in ("realizable", "unrealizable"))
    series = [
        ("fire_patrol_explicit", example_path("fire_patrol_explicit"), "ExplicitFirePatrol",
         explicit_fire_patrol),
        ("ordered_patrol", example_path("ordered_patrol"), "OrderedPatrol",
         lambda n: with_constant(example_path("ordered_patrol").read_text(), "N", n)),
    ]
    for name, path, composite, make in series:
        timed_out = False
        # Ordered Patrol needs N >= 2 (its Due fluents would not be disjoint for N = 1).
        for n in (ns if name != "ordered_patrol" else [n for n in ns if n >= 2]):
            if timed_out:
                rows.append(Row(name, n, "skipped", float("nan"), float("nan"), None,
                                "previous N timed out"))
            else:
                rows.append(measure(name, n, path, make(n), composite, budget_s))
                timed_out = rows[-1].status == "timeout"
            if progress:
                progress.update(rows[-1].status in ("realizable", "unrealizable"))
    return rows


def _warm_up() -> None:
    """Load the parser (and the synthesis modules) once in this process, so the forked children
    measure elaboration and synthesis rather than grammar loading and imports."""
    try:
        from iterplan_compiler.frontend import load
        from iterplan_compiler.synthesis import driver  # noqa: F401

        load("warm-up.lts", "W = (a -> W).")
    except Exception:  # warm-up is an optimisation only; the real run reports any problem
        pass


def format_table(rows: list[Row]) -> str:
    """Plain-text table (the benchmark prints it)."""
    head = f"{'spec':<22} {'N':>3} {'status':<12} {'front-end s':>11} {'synthesis s':>11} " \
           f"{'states':>9}  note"
    lines = [head, "-" * len(head)]
    for r in rows:
        n = "any" if r.n is None else str(r.n)
        st = "" if r.states is None else str(r.states)
        lines.append(f"{r.spec:<22} {n:>3} {r.status:<12} {_s(r.load_s):>11} "
                     f"{_s(r.synth_s):>11} {st:>9}  {r.detail}")
    return "\n".join(lines)


def _s(x: float) -> str:
    return "" if x != x else f"{x:.3f}"  # NaN -> blank


def rows_csv(rows: list[Row]) -> str:
    out = ["spec,n,status,load_s,synth_s,states"]
    for r in rows:
        out.append(f"{r.spec},{'' if r.n is None else r.n},{r.status},{_s(r.load_s)},"
                   f"{_s(r.synth_s)},{'' if r.states is None else r.states}")
    return "\n".join(out) + "\n"
