"""Resource bombs (issue 14): each ends within seconds, exit 1, with a diagnostic that names
the limit reached and the flag that raises it; peak memory stays far below 2 GB.

Each bomb runs ``iterc`` as a real subprocess (so the watchdog of limits.py is on, as for a
user).  Time is measured as the child's CPU time (user + sys, from ``wait4``): the CI machine
may be shared, and wall time then says more about the neighbours than about iterc."""

from __future__ import annotations

import subprocess
import sys
import time

import pytest

CPU_BUDGET_S = 10.0
RSS_BUDGET_KB = 2 * 1024 * 1024


def _spec_const_squarings() -> str:
    # 800 bytes: each constant squares the previous one (unbounded integers)
    lines = ["const C0 = 3"] + [f"const C{i} = C{i - 1} * C{i - 1}" for i in range(1, 40)]
    return "\n".join(lines) + "\nP = (a -> P).\n"


def _spec_toggles(n: int = 20) -> str:
    procs = [f"T{i} = (on{i} -> off{i} -> T{i})." for i in range(n)]
    acts = ", ".join(f"on{i}" for i in range(n))
    return "\n".join([*procs, "fluent Goal = <on0, off0>", "assert G = Goal",
                      f"controllerSpec Spec = {{\n  liveness = {{G}}\n  controllable = {{{acts}}}\n}}",
                      "controller ||C = (" + " || ".join(f"T{i}" for i in range(n)) + ")~{Spec}.",
                      ""])


def _spec_million_states() -> str:
    return ("T(I=0) = (t[I] -> u[I] -> T).\n"
            "||C = (" + " || ".join(f"x{i}:T({i})" for i in range(20)) + ").\n"
            "fluent F = <x0.t[0], x0.u[0]>\nassert A = []<>F\n")


def _spec_nested_next(n: int = 30) -> str:
    return "A = (a -> b -> A).\nfluent F = <a, b>\nassert P = " + "X " * n + "F\n"


def _spec_until_disjuncts(n: int = 24) -> str:
    procs = "\n".join(f"P{i} = (a{i} -> b{i} -> P{i})." for i in range(n + 1))
    fl = "\n".join(f"fluent F{i} = <a{i}, b{i}>" for i in range(n + 1))
    prop = "ltl_property Q = (" + " || ".join(f"(F{i} U F{i + 1})" for i in range(n)) + ")\n"
    return f"{procs}\n{fl}\n{prop}||S = (P0 || P1 || Q).\n"


def _spec_many_processes(n: int = 100_000) -> str:
    return "\n".join(f"P{i} = (a{i} -> P{i})." for i in range(n)) + "\n"


# name, spec text, iterc arguments (SPEC is replaced by the file), code, flag in the message
BOMBS = [
    ("const-squarings", _spec_const_squarings, ["check", "SPEC"], "E0208", "--max-int-bits"),
    ("synthesis-20-toggles", _spec_toggles, ["synth", "SPEC"], "E0402", "--max-states"),
    ("verify-1M-states", _spec_million_states, ["verify", "SPEC", "--assert", "A", "--on", "C"],
     "E0402", "--max-states"),
    ("assert-30-nested-X", _spec_nested_next, ["verify", "SPEC", "--assert", "P", "--on", "A"],
     "E0603", "--max-temporal-depth"),
    ("ltl_property-24-Until-disjuncts", _spec_until_disjuncts, ["check", "--build", "SPEC"],
     "E0603", "--max-temporal-ops"),
    ("100k-process-definitions", _spec_many_processes, ["check", "SPEC"], "E0006",
     "--max-declarations"),
    # the backstops: a limit raised past what the machine can do in seconds
    ("time-limit", _spec_until_disjuncts,
     ["check", "--build", "SPEC", "--max-temporal-ops", "100", "--time-limit", "3"],
     "E0404", "--time-limit"),
    ("memory-limit", _spec_million_states,
     ["verify", "SPEC", "--assert", "A", "--on", "C", "--max-states", "100000000",
      "--max-memory", "250"], "E0405", "--max-memory"),
]


def run_measured(argv: list[str], timeout: float = 120.0):
    """Run ``iterc argv`` as a subprocess; (exit code, stderr, wall seconds)."""
    t0 = time.monotonic()
    proc = subprocess.Popen([sys.executable, "-m", "iterplan_compiler", *argv],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        _, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
    # CPU time and peak RSS: the caller reads RUSAGE_CHILDREN around this call
    return proc.returncode, err.decode("utf-8", "replace"), time.monotonic() - t0


@pytest.mark.parametrize("name,make,args,code,flag", BOMBS, ids=[b[0] for b in BOMBS])
def test_bomb_ends_fast_with_the_limit_named(name, make, args, code, flag, tmp_path):
    import resource

    spec = tmp_path / f"{name}.lts"
    spec.write_text(make())
    argv = [str(spec) if a == "SPEC" else a for a in args]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    rc, err, wall = run_measured(argv)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    assert rc == 1, (rc, err[-3000:])
    assert f"error[{code}]" in err and flag in err, err[-3000:]
    assert "Traceback" not in err
    assert cpu < CPU_BUDGET_S, f"{name}: {cpu:.1f} s CPU ({wall:.1f} s wall)"
    # ru_maxrss of children is the largest child so far: a bound for this one too
    assert after.ru_maxrss < RSS_BUDGET_KB, f"{name}: peak RSS {after.ru_maxrss} KB"


def test_limits_documented_once():
    from iterplan_compiler import limits

    doc = limits.__doc__ or ""
    for flag, _what in limits.FLAGS.values():
        assert flag in doc, flag


def test_limit_flags_are_on_the_compiler_commands(capsys):
    from iterplan_compiler import cli

    with pytest.raises(SystemExit):
        cli.main(["check", "--help"])
    out = capsys.readouterr().out
    for flag in ("--max-int-bits", "--max-states", "--max-temporal-depth", "--time-limit",
                 "--max-memory", "--max-declarations", "--max-temporal-ops"):
        assert flag in out


def test_raising_a_limit_lets_the_input_through(tmp_path, capsys):
    from iterplan_compiler import cli, limits

    spec = tmp_path / "c.lts"
    spec.write_text("const A = 2 ** 2000\nP = (a -> P).\n")
    try:
        assert cli.main(["check", str(spec)]) == 1
        assert "--max-int-bits" in capsys.readouterr().err
        assert cli.main(["check", str(spec), "--max-int-bits", "4096"]) == 0
    finally:
        limits.set_limits(limits.DEFAULT)

