"""Mutation fuzzer of the exit-code contract (issue 14): specs through ``iterc check --build``
(parse, elaborate, compose, synthesise) and maps through ``grid.load_map``.

Seeds: the bundled examples, the stdlib, the golden spec and the MTSA conformance corpus
(``../shared/conformance/mtsa`` when present) for specs; the example maps plus generated
variants for maps.  Each input is a seed with 1-4 random edits (token- and character-level
for specs, value/key/structure edits for maps).  An input *fails* the contract when

* ``iterc`` returns 3 or lets an exception escape (a traceback), or a map raises anything but
  ``MapError``;
* it runs longer than ``--timeout`` seconds (a resource limit that did not fire).

Specs run with ``--time-limit 5 --max-states 20000`` (so a mutation that asks for a huge
game ends in a limit diagnostic, which is a pass, instead of minutes of synthesis).

Inputs run in worker processes (one per core) so a hang is killed and counted, not waited
for.  Failing inputs are saved to ``--save DIR`` to become regression tests.

    python tests/robustness/fuzz.py spec --count 100000        # the issue's 100,000 run
    python tests/robustness/fuzz.py map --count 100000
    python tests/robustness/fuzz.py spec --seconds 60          # what .ci/run does (bounded)

Exit status 0 if no input failed, 1 otherwise.  Deterministic for a given ``--seed``.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import multiprocessing as mp
import os
import random
import re
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
CORPUS = REPO.parent / "shared" / "conformance" / "mtsa"

TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_.]*|\d+|\.\.|->|\|\||<->|&&|[^\sA-Za-z0-9_]|\s+")
EXTRA = ["(", ")", "{", "}", "[", "]", ".", ",", "|", "||", "->", "~", "\\", "@", "/", "'",
         '"', "\x00", "\ufffd", "é", "0..2", "-1", "99999", "if", "then", "else", "when",
         "range", "const", "set", "fluent", "assert", "controller", "include", "ERROR", "STOP",
         "END", "tau", "property", "minimal", "deterministic", "forall", "+", "*", ":", ";",
         "<>", "[]", "X", "U", "W", "!", "=", "\n", "9" * 5000, "0x" + "f" * 3000, "**",
         "<<", "ltl_property", "ltl_property P = X X X X X X X X X X X X X X a\n",
         'include "' + "a" * 5000 + '"\n', "const Q = (2**2**2**2**2)\n", "1.5", "0..999999",
         "P(N=1) = (a -> P(N+1)).\n", "\u202e", "\r\n"]


# ------------------------------------------------------------------ seeds and mutations


def spec_seeds() -> list[tuple[str, str]]:
    paths = sorted((REPO / "examples").glob("*.lts")) + sorted((REPO / "stdlib").glob("*.lts"))
    paths.append(REPO / "tests" / "data" / "golden" / "patrol.lts")
    if CORPUS.is_dir():
        paths += sorted(CORPUS.rglob("*.lts"))
    return [(p.name, p.read_text(encoding="utf-8", errors="replace")) for p in paths]


def mutate(text: str, ops: list[tuple[int, int, int, int]], extra: list[str] = EXTRA) -> str:
    """Apply ``(op, i, j, k)`` edits to the token list of ``text`` (indices taken modulo):
    0 delete, 1 duplicate, 2 swap, 3 overwrite a token, 4 insert a fragment of ``extra``,
    5 drop / 6 duplicate one character, 7 duplicate a whole line elsewhere (declarations,
    nesting).  Shared with the hypothesis fuzz test (tests/cli/test_cli_fuzz.py)."""
    toks = TOKEN.findall(text)
    for op, i, j, k in ops:
        if not toks:
            toks = [extra[k % len(extra)]]
            continue
        i %= len(toks)
        j %= len(toks)
        if op == 0:
            del toks[i]
        elif op == 1:
            toks.insert(i, toks[i])
        elif op == 2:
            toks[i], toks[j] = toks[j], toks[i]
        elif op == 3:
            toks[i] = toks[j]
        elif op == 4:
            toks.insert(i, extra[k % len(extra)])
        elif op == 5 and toks[i]:
            s = toks[i]
            toks[i] = s[: k % len(s)] + s[k % len(s) + 1:]
        elif op == 7:
            lines = "".join(toks).splitlines(keepends=True) or [""]
            lines.insert(k % (len(lines) + 1), lines[i % len(lines)])
            toks = TOKEN.findall("".join(lines))
        else:
            s = toks[i] or " "
            toks[i] = s[: k % len(s)] + s[k % len(s)] + s[k % len(s):]
    return "".join(toks)


def mutate_spec(text: str, rng: random.Random) -> str:
    """1-4 random edits of :func:`mutate`."""
    big = 1 << 30
    ops = [(rng.randrange(8), rng.randrange(big), rng.randrange(big), rng.randrange(big))
           for _ in range(rng.randint(1, 4))]
    return mutate(text, ops)


def map_seeds() -> list[tuple[str, object]]:
    seeds: list[tuple[str, object]] = []
    for p in sorted((REPO / "examples").glob("*.json")):
        seeds.append((p.name, json.loads(p.read_text())))
    seeds.append(("bbox", {"bbox": [-35.37, 149.16, -35.36, 149.17], "cell_size": 100,
                           "sensors": {"a": {"random": 0.2, "seed": 3}}}))
    seeds.append(("polygon", {"polygon": {"type": "Polygon", "coordinates": [[
        [149.1653, -35.3632], [149.1680, -35.3632], [149.1680, -35.3610],
        [149.1653, -35.3632]]]}, "cell_size": 40, "home": [-35.3630, 149.1655],
        "sensors": {"g": {"type": "FeatureCollection", "features": [
            {"type": "Feature", "properties": {}, "geometry": {
                "type": "MultiPoint", "coordinates": [[149.1660, -35.3628]]}}]}}}))
    return seeds


ODD_VALUES = [None, True, False, 0, -1, 1, 2**64, -(2**64), 1e308, -1e308, math.nan, math.inf,
              -math.inf, 0.5, "", "A1", "Z99", "x" * 300, [], {}, [0], [1, 2, 3], [90, 0],
              [0, 200], [-35.36, 149.16, 10], {"cell": "A1"}, {"rect": [0, 0, 1, 1]},
              {"random": 0.5}, {"file": "nope.txt"}, {"type": "Point", "coordinates": [1, 2]},
              {"type": "LineString"}, 10**6, 100_000, "NaN", [[0, 0], [0, 1], [1, 1]]]


def _paths(obj, prefix=()):
    yield prefix
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _paths(v, (*prefix, i))


def _set(obj, path, value):
    if not path:
        return value
    cur = obj
    for p in path[:-1]:
        cur = cur[p]
    cur[path[-1]] = value
    return obj


def mutate_map(data, rng: random.Random):
    obj = json.loads(json.dumps(data))
    for _ in range(rng.randint(1, 4)):
        paths = list(_paths(obj))
        path = rng.choice(paths)
        op = rng.randrange(5)
        cur = obj
        for p in path:
            cur = cur[p]
        if op == 0 or not path:
            obj = _set(obj, path, json.loads(json.dumps(rng.choice(ODD_VALUES))))
        elif op == 1 and isinstance(cur, int | float) and not isinstance(cur, bool):
            obj = _set(obj, path, cur * rng.choice([-1, 10, 1000, 1e9, 0]))
        elif op == 2:  # delete
            parent = obj
            for p in path[:-1]:
                parent = parent[p]
            del parent[path[-1]]
        elif op == 3 and isinstance(cur, list) and cur:
            cur.append(rng.choice(cur))
        elif op == 4 and isinstance(cur, dict):
            cur[rng.choice(["extra", "cols", "rows", "bbox", "polygon", "origin", "home",
                            "dynamic", "derived", "cells", "type"])] = \
                json.loads(json.dumps(rng.choice(ODD_VALUES)))
        if not isinstance(obj, dict | list):
            break
    return obj


# ------------------------------------------------------------------ running one input


def run_spec(name: str, text: str, workdir: str) -> str | None:
    """None if the contract held, else what went wrong."""
    from iterplan_compiler import cli

    path = os.path.join(workdir, name if name.endswith(".lts") else name + ".lts")
    with open(path, "w", encoding="utf-8", errors="surrogatepass") as f:
        f.write(text)
    out, err = io.StringIO(), io.StringIO()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            rc = cli.main(["check", "--build", "--quiet", "--time-limit", "5",
                           "--max-states", "20000", path])
    except SystemExit as e:  # argparse
        rc = e.code if isinstance(e.code, int) else 2
    except BaseException as e:  # noqa: BLE001 - exactly what the fuzzer looks for
        return f"exception {type(e).__name__}: {e}"
    text_out = out.getvalue() + err.getvalue()
    if rc == 3 or "Traceback (most recent call last)" in text_out:
        return f"exit {rc}: {text_out[-2000:]}"
    return None


def run_map(name: str, data, workdir: str) -> str | None:
    from iterplan_compiler.runtime.grid import MapError
    from iterplan_compiler.runtime.mapfile import load_map

    path = os.path.join(workdir, "map.json")
    with open(path, "w") as f:
        json.dump(data, f, allow_nan=True)
    try:
        load_map(path)
    except MapError:
        return None
    except BaseException as e:  # noqa: BLE001
        return f"exception {type(e).__name__}: {e}"
    return None


def _worker(conn, kind: str) -> None:
    workdir = tempfile.mkdtemp(prefix="iterplan-fuzz-")
    os.chdir(workdir)
    fn = run_spec if kind == "spec" else run_map
    while True:
        item = conn.recv()
        if item is None:
            return
        i, name, payload = item
        conn.send((i, fn(name, payload, workdir)))


class _Slot:
    def __init__(self, kind: str):
        self.kind = kind
        self.start()

    def start(self) -> None:
        ctx = mp.get_context("fork" if sys.platform != "win32" else "spawn")
        self.conn, child = ctx.Pipe()
        self.proc = ctx.Process(target=_worker, args=(child, self.kind), daemon=True)
        self.proc.start()
        self.busy: tuple | None = None
        self.t0 = 0.0

    def restart(self) -> None:
        self.proc.kill()
        self.proc.join()
        self.start()


def fuzz(kind: str, count: int | None, seconds: float | None, seed: int, timeout: float,
         jobs: int, save: Path | None, quiet: bool) -> dict:
    rng = random.Random(seed)
    seeds = spec_seeds() if kind == "spec" else map_seeds()
    mutate = mutate_spec if kind == "spec" else mutate_map
    slots = [_Slot(kind) for _ in range(jobs)]
    stats = {"inputs": 0, "failed": 0, "timeouts": 0, "seconds": 0.0}
    failures: list[tuple[str, object, str]] = []
    t_start = time.monotonic()
    issued = 0

    def more() -> bool:
        if count is not None and issued >= count:
            return False
        return seconds is None or time.monotonic() - t_start < seconds

    def record(item, why: str) -> None:
        stats["failed"] += 1
        failures.append((item[1], item[2], why))
        if save is not None:
            save.mkdir(parents=True, exist_ok=True)
            ext = ".lts" if kind == "spec" else ".json"
            body = item[2] if kind == "spec" else json.dumps(item[2], allow_nan=True)
            (save / f"{kind}-{seed}-{item[0]}{ext}").write_text(
                body, encoding="utf-8", errors="surrogatepass")
            (save / f"{kind}-{seed}-{item[0]}.why").write_text(why)
        if not quiet:
            print(f"FAIL #{item[0]} ({item[1]}): {why[:300]}", file=sys.stderr)

    last_report = time.monotonic()
    while True:
        for s in slots:
            if s.busy is None and more():
                name, base = rng.choice(seeds)
                item = (issued, name, mutate(base, rng))
                issued += 1
                s.busy, s.t0 = item, time.monotonic()
                s.conn.send(item)
        active = [s for s in slots if s.busy is not None]
        if not active:
            break
        ready = mp.connection.wait([s.conn for s in active], timeout=0.5)
        now = time.monotonic()
        for s in active:
            if s.conn in ready:
                try:
                    _i, why = s.conn.recv()
                except EOFError:  # the worker died (e.g. killed by the OS)
                    why = "worker died"
                    s.restart()
                stats["inputs"] += 1
                if why is not None:
                    record(s.busy, why)
                s.busy = None
            elif now - s.t0 > timeout:
                stats["inputs"] += 1
                stats["timeouts"] += 1
                record(s.busy, f"timeout: still running after {timeout:g} s")
                s.restart()
        if not quiet and now - last_report > 30:
            last_report = now
            print(f"  {stats['inputs']:,} inputs, {stats['failed']} failed, "
                  f"{now - t_start:.0f} s", file=sys.stderr)
    for s in slots:
        with contextlib.suppress(Exception):
            s.conn.send(None)
        s.proc.join(timeout=5)
        if s.proc.is_alive():
            s.proc.kill()
    stats["seconds"] = round(time.monotonic() - t_start, 1)
    stats["failures"] = [(n, w[:500]) for n, _p, w in failures[:20]]
    return stats


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("kind", choices=("spec", "map"))
    ap.add_argument("--count", type=int, default=None, help="number of inputs")
    ap.add_argument("--seconds", type=float, default=None, help="time budget")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--timeout", type=float, default=20.0, help="seconds per input")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--save", type=Path, default=None, help="save failing inputs here")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)
    if a.count is None and a.seconds is None:
        a.count = 1000
    stats = fuzz(a.kind, a.count, a.seconds, a.seed, a.timeout, max(1, a.jobs), a.save,
                 a.quiet)
    print(json.dumps(stats, indent=1))
    return 1 if stats["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())
