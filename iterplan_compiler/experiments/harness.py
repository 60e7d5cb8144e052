"""Run experiment cases, in parallel, with a progress bar; collect rows; write CSV.

A *runner* is a picklable callable ``runner(case) -> dict`` returning at least ``duration``
and ``ideal`` (seconds); it may add more numeric fields.  A runner that raises is recorded as
a failed row (``error`` column) rather than aborting the sweep: one crashed simulation must not
throw away hours of others.

Executors: ``jobs == 1`` runs in this process (deterministic order, easiest to debug);
``jobs > 1`` starts a ``dask.distributed`` :class:`LocalCluster` of ``jobs`` single-threaded
worker processes (the ``experiments`` extra; without it a
:class:`concurrent.futures.ProcessPoolExecutor`); a scheduler address (``--scheduler
tcp://host:8786``) runs the cases on that Dask cluster, past one machine.
"""

from __future__ import annotations

import concurrent.futures as cf
import csv
import dataclasses
import io
import math
import sys
import time
from collections import defaultdict
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import TextIO

from iterplan_compiler.experiments.stats import overhead, summarize
from iterplan_compiler.experiments.sweeps import Case
from iterplan_compiler.outputs import atomic_write_text

Runner = Callable[[Case], dict]

CASE_FIELDS = [f.name for f in dataclasses.fields(Case)]
RESULT_FIELDS = ["duration", "ideal", "overhead_pct", "wall_s", "error"]


class ExperimentError(RuntimeError):
    """A sweep cannot run (e.g. a missing optional dependency); the message is for the user."""


class Progress:
    """A tqdm progress bar on ``stream`` (stderr): redrawn in place on a terminal; elsewhere
    (CI logs) a line at most every 30 s."""

    def __init__(self, total: int, label: str, stream: TextIO | None = None,
                 enabled: bool = True):
        from tqdm import tqdm

        self.total, self.label, self.done, self.failed = total, label, 0, 0
        self.stream = stream if stream is not None else sys.stderr
        tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.enabled = enabled
        self._bar = tqdm(total=total, desc=label, file=self.stream, disable=not enabled,
                         mininterval=0.2 if tty else 30.0, ascii=not tty, unit="run",
                         dynamic_ncols=tty)

    def update(self, ok: bool = True) -> None:
        self.done += 1
        self.failed += 0 if ok else 1
        if self.failed:
            self._bar.set_postfix(failed=self.failed, refresh=False)
        self._bar.update(1)
        if self.done >= self.total:
            self._bar.close()


def _run_one(runner: Runner, case: Case) -> dict:
    """Run one case, never raising: failures become a row with ``error`` set."""
    t0 = time.perf_counter()
    row: dict = dict(zip(CASE_FIELDS, case.values(), strict=True))
    try:
        res = dict(runner(case))
        row.update(res)
        row["overhead_pct"] = overhead(float(res["duration"]), float(res["ideal"]))
        row["error"] = ""
    except Exception as exc:  # a failed simulation is data, not a crash of the sweep
        row.update(duration=math.nan, ideal=math.nan, overhead_pct=math.nan,
                   error=f"{type(exc).__name__}: {exc}".replace("\n", " ")[:300])
    row["wall_s"] = round(time.perf_counter() - t0, 3)
    return row


def run_cases(cases: Sequence[Case], runner: Runner, *, jobs: int = 1,
              scheduler: str | None = None, progress: Progress | None = None,
              on_row: Callable[[dict], None] | None = None) -> list[dict]:
    """Run every case; rows come back in the order of ``cases`` whatever the executor.
    ``on_row`` sees each row as soon as its mission ends (e.g. to save partial results of a
    sweep that takes hours)."""
    rows: list[dict | None] = [None] * len(cases)

    def done(i: int, row: dict) -> None:
        rows[i] = row
        if on_row is not None:
            on_row(row)
        if progress is not None:
            progress.update(ok=not row.get("error"))

    if scheduler or (jobs > 1 and dask_available()):
        try:
            from dask.distributed import Client, LocalCluster, as_completed
        except ImportError:
            raise ExperimentError("--scheduler needs dask.distributed "
                                  "(pip install 'iterplan[experiments]')") from None
        cluster = None
        if scheduler:
            client = Client(scheduler)
        else:   # one single-threaded worker process per job: missions are CPU-bound Python
            cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            client = Client(cluster)
        try:
            futures = {client.submit(_run_one, runner, c, pure=False): i
                       for i, c in enumerate(cases)}
            for fut in as_completed(futures):
                done(futures[fut], fut.result())
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    elif jobs <= 1:
        for i, case in enumerate(cases):
            done(i, _run_one(runner, case))
    else:
        with cf.ProcessPoolExecutor(max_workers=jobs) as pool:
            futs = {pool.submit(_run_one, runner, c): i for i, c in enumerate(cases)}
            for fut in cf.as_completed(futs):
                done(futs[fut], fut.result())
    return [r for r in rows if r is not None]


def dask_available() -> bool:
    """True when ``dask.distributed`` can be imported (the ``experiments`` extra)."""
    import importlib.util

    return importlib.util.find_spec("distributed") is not None


def extra_fields(rows: Iterable[dict]) -> list[str]:
    known = set(CASE_FIELDS) | set(RESULT_FIELDS)
    return sorted({k for r in rows for k in r if k not in known})


def write_csv(rows: Sequence[dict], path: Path | None = None) -> str:
    """Write the per-run rows as CSV (to ``path`` if given); return the text."""
    fields = CASE_FIELDS + RESULT_FIELDS + extra_fields(rows)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=fields, lineterminator="\n", extrasaction="ignore")
    w.writeheader()
    for r in rows:
        w.writerow({k: _fmt(r.get(k, "")) for k in fields})
    text = buf.getvalue()
    if path is not None:
        atomic_write_text(path, text)
    return text


def _fmt(v):
    if isinstance(v, float):
        return "" if math.isnan(v) else f"{v:.6g}"
    return v


@dataclasses.dataclass(frozen=True)
class Point:
    """One aggregated point of a plot: the mean ± 3 SEM of a metric over the seeds."""

    experiment: str
    universe: int
    count: int
    sorter: str
    n: int
    duration: float
    duration_err3: float
    ideal: float
    overhead_pct: float
    overhead_err3: float
    failed: int
    #: the kinematic floor over the ideal (%): what the turn radius costs at least
    physics_pct: float = math.nan
    physics_err3: float = math.nan
    #: fig3b: the first patrol loop's overhead (%), when loops after a warm-up are measured
    #: (runs with ``warmup`` > 0; else NaN: the first loop is in ``duration``)
    first_loop_pct: float = math.nan
    first_loop_err3: float = math.nan
    #: fig3b: seconds from the mission's start (after take-off) to the first visit of p.0
    launch_s: float = math.nan
    launch_err3: float = math.nan


def aggregate(rows: Iterable[dict]) -> list[Point]:
    """Group rows by (experiment, universe, count, sorter) and summarise them."""
    groups: dict[tuple, list[dict]] = defaultdict(list)
    for r in rows:
        groups[(r["experiment"], int(r["universe"]), int(r["count"]), r["sorter"])].append(r)
    points = []
    for key in sorted(groups):
        rs = groups[key]
        ok = [r for r in rs if not r.get("error")]
        d = summarize(float(r["duration"]) for r in ok)
        o = summarize(float(r["overhead_pct"]) for r in ok)
        ideal = summarize(float(r["ideal"]) for r in ok).mean
        ph = summarize(_num(r.get("physics_pct")) for r in ok)
        first = summarize(100.0 * (_num(r.get("first_loop")) - float(r["ideal"]))
                          / float(r["ideal"]) for r in ok if _num(r.get("warmup")) > 0)
        launch = summarize(_num(r.get("launch")) for r in ok)
        points.append(Point(key[0], key[1], key[2], key[3], n=d.n, duration=d.mean, duration_err3=d.err3, ideal=ideal,
                            overhead_pct=o.mean, overhead_err3=o.err3,
                            failed=len(rs) - len(ok), physics_pct=ph.mean,
                            physics_err3=ph.err3, first_loop_pct=first.mean,
                            first_loop_err3=first.err3, launch_s=launch.mean,
                            launch_err3=launch.err3))
    return points


def _num(v: object) -> float:
    try:
        return float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return math.nan


def write_summary_csv(points: Sequence[Point], path: Path | None = None) -> str:
    fields = [f.name for f in dataclasses.fields(Point)]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=fields, lineterminator="\n")
    w.writeheader()
    for p in points:
        w.writerow({k: _fmt(v) for k, v in dataclasses.asdict(p).items()})
    text = buf.getvalue()
    if path is not None:
        atomic_write_text(path, text)
    return text
