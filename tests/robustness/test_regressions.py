"""The crashing inputs of issue 14, pinned through the CLI: each one is a diagnostic with a
code and exit 1 -- never exit 3, never a traceback -- and bounded hypothesis fuzz targets for
the parser + elaborator and for the map loader (the long runs: ``tests/robustness/fuzz.py``).
"""

from __future__ import annotations

import json
import random
import sys
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from iterplan_compiler import cli, limits, pipeline

sys.path.insert(0, str(Path(__file__).resolve().parent))
import fuzz  # noqa: E402 - the mutation engine shared with the long runs

REGRESSIONS = [
    # (what, spec text, expected code)
    ("decimal literal over 4,300 digits", "const N = " + "9" * 5000 + "\nP = (a -> P).\n",
     "E0208"),
    ("literal in a range", "range R = 0.." + "7" * 4400 + "\nP = (a[i:R] -> P).\n", "E0208"),
    ("real literal over 4,300 digits", "const N = 1." + "1" * 5000 + "\nP = (a -> P).\n",
     "E0208"),
    ("hex literal of 20,000 digits", "const N = 0x" + "f" * 20_000 + "\nP = (a -> P).\n",
     "E0208"),
    ("literal in a spec field", "controllerSpec S = {\n  liveness = {}\n  controllable = {a}\n"
     "  lazyness = " + "9" * 5000 + "\n}\nP = (a -> P).\n", "E0208"),
    ("include name too long for the OS", 'include "' + "a" * 5000 + '.lts"\nP = (a -> P).\n',
     "E0801"),
    ("include name with a NUL byte", 'include "a\x00b.lts"\nP = (a -> P).\n', "E0801"),
    ("const squarings", "const C0 = 3\n" + "".join(f"const C{i} = C{i-1} * C{i-1}\n"
                                                    for i in range(1, 30)) + "P = (a -> P).\n",
     "E0208"),
    ("power of a power", "const A = (2 ** (2 ** 40))\nP = (a -> P).\n", "E0208"),
    ("shift by a huge count", "const A = (1 << 100000000)\nP = (a -> P).\n", "E0208"),
    ("negative shift", "const A = (1 << -1)\nP = (a -> P).\n", "E0202"),
    ("zero to a negative power", "const A = (0 ** -1)\nP = (a -> P).\n", "E0203"),
    ("infinite parameter recursion", "P(N=1) = (a -> P(N+1)).\n||S = (P(1)).\n", "E0307"),
    ("a process instance including itself", "P(N=1) = (a -> P(1)).\n||S = (P(1)).\n",
     "E0307"),
    ("30 nested X", "A = (a -> A).\nfluent F = <a, a>\nltl_property P = " + "X " * 30
     + "[]!F\n||S = (A || P).\n", "E0603"),
]


@pytest.mark.parametrize("what,text,code", REGRESSIONS, ids=[r[0] for r in REGRESSIONS])
def test_crashing_input_is_a_diagnostic(what, text, code, tmp_path, capsys):
    spec = tmp_path / "x.lts"
    spec.write_text(text, encoding="utf-8")
    rc = cli.main(["check", "--build", str(spec)])
    err = capsys.readouterr().err
    assert rc == 1, err[-2000:]
    assert f"error[{code}]" in err, err[-2000:]
    assert "Traceback" not in err and "internal error" not in err


def test_internal_exception_in_synthesis_is_exit_3_not_e0901(tmp_path, capsys, monkeypatch):
    """A bug in synthesis must not be disguised as "synthesis failed" (E0901, exit 1)."""
    from iterplan_compiler.synthesis import driver

    def broken(*_a, **_k):
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr(driver, "synthesize", broken)
    fire = Path(__file__).resolve().parents[2] / "examples" / "fire_patrol.lts"
    rc = cli.main(["check", "--build", str(fire)])
    err = capsys.readouterr().err
    assert rc == 3, err[-2000:]
    assert "E0901" not in err and "internal error" in err


def test_unsupported_goal_is_still_e0901(tmp_path, capsys):
    spec = tmp_path / "g.lts"
    spec.write_text("A = (a -> b -> A).\nfluent F = <a, b>\nassert G = <>F\n"
                    "controllerSpec S = {\n  liveness = {G}\n  controllable = {a}\n}\n"
                    "controller ||C = (A)~{S}.\n")
    rc = cli.main(["check", "--build", str(spec)])
    err = capsys.readouterr().err
    assert rc == 1 and "Traceback" not in err and "internal error" not in err


# ------------------------------------------------------------------ bounded fuzz targets

SPEC_SEEDS = fuzz.spec_seeds()
MAP_SEEDS = fuzz.map_seeds()


@pytest.fixture
def small_limits():
    previous = limits.set_limits(max_states=5_000, time_limit=20)
    yield
    limits.set_limits(previous)


@settings(max_examples=60, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(seed=st.sampled_from(SPEC_SEEDS), r=st.integers(0, 2**32 - 1))
def test_fuzz_parser_and_elaborator(small_limits, seed, r):
    name, text = seed
    mutated = fuzz.mutate_spec(text, random.Random(r))
    model, diags = pipeline.load_model(name, text=mutated)
    if model is not None:
        for n in model.own_names():
            model.build_lts(n)


@settings(max_examples=300, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.sampled_from(MAP_SEEDS), r=st.integers(0, 2**32 - 1))
def test_fuzz_map_loader(seed, r, tmp_path):
    from iterplan_compiler.runtime.grid import MapError
    from iterplan_compiler.runtime.mapfile import load_map

    _name, data = seed
    mutated = fuzz.mutate_map(data, random.Random(r))
    p = tmp_path / "m.json"
    p.write_text(json.dumps(mutated, allow_nan=True))
    try:
        load_map(p)
    except MapError as exc:
        assert str(exc).startswith(str(p)) or "cannot read" in str(exc), str(exc)


CORPUS = Path(__file__).resolve().parents[3] / "shared" / "conformance" / "mtsa"


@pytest.mark.skipif(not (CORPUS / "FSP" / "SLBD-V5.lts").is_file(),
                    reason="the MTSA conformance corpus (../shared) is not present")
def test_fuzz_found_slow_safety_automaton_honours_the_time_limit(tmp_path, capsys):
    """Found by tests/robustness/fuzz.py (seed 14, input 21299): SLBD-V5 with N = 22 cars makes
    an ltl_property over 44 fluents, whose automaton is explored for minutes; --time-limit
    must stop it (checked every 64 automaton states) with E0404."""
    text = (CORPUS / "FSP" / "SLBD-V5.lts").read_text()
    assert "const N = 2/" in text
    spec = tmp_path / "slbd.lts"
    spec.write_text(text.replace("const N = 2/", "const N = 22/", 1))
    t0 = time.monotonic()
    rc = cli.main(["check", "--build", "--quiet", "--time-limit", "3", str(spec)])
    err = capsys.readouterr().err
    assert rc == 1 and "error[E0404]" in err and "--time-limit" in err, err[-2000:]
    assert time.monotonic() - t0 < 30  # 3 s plus the work between two checks, under load
