"""`iterc solve`, `iterc run`, `iterc conformance`, `iterc experiment` on bad input, and a few
runs of the real ``iterc`` process (entry point, exit status, no traceback on stderr)."""

from __future__ import annotations

import subprocess
import sys

import pytest
from cli_helpers import FIRE_MAP, GOLDEN_SPEC, assert_input_error, assert_no_crash, run_cli

GARBAGE = bytes(range(256)) * 2


@pytest.fixture
def write(tmp_path):
    def _write(name: str, data: bytes | str):
        path = tmp_path / name
        path.write_bytes(data.encode("utf-8") if isinstance(data, str) else data)
        return path
    return _write


# --- iterc solve (slugsin) ------------------------------------------------------------------

def test_solve_missing_file(tmp_path, capsys):
    missing = tmp_path / "nope.slugsin"
    assert_input_error(run_cli(capsys, "solve", missing), missing, code="G100")


def test_solve_text_before_header(write, capsys):
    spec = write("bad.slugsin", "x0\n[INPUT]\nx0\n")
    assert_input_error(run_cli(capsys, "solve", spec), spec, located=True)


def test_solve_small_spec(write, capsys):
    spec = write("t.slugsin", "[INPUT]\nx0\n[OUTPUT]\ny0\n[SYS_LIVENESS]\ny0\n")
    res = run_cli(capsys, "solve", spec)
    assert_no_crash(res)
    assert res.code == 0 and "REALIZABLE" in res.out


def test_solve_binary_garbage(write, capsys):
    spec = write("garbage.slugsin", GARBAGE)
    assert_input_error(run_cli(capsys, "solve", spec), spec)


# --- iterc run ------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def controller_module(tmp_path_factory):
    from iterplan_compiler import cli

    path = tmp_path_factory.mktemp("ctl") / "patrol_ctl.py"
    assert cli.main(["compile", str(GOLDEN_SPEC), "-o", str(path)]) == 0
    return path


@pytest.mark.parametrize("name,data,needle", [
    ("missing.py", None, "not found"),
    ("garbage.lts", GARBAGE, "not a Python module"),
    ("badsyntax.py", "def (:\n", "SyntaxError"),
    ("badimport.py", "import no_such_module_qa\n", "ModuleNotFoundError"),
    ("notctl.py", "X = 1\n", "defines no controller"),
])
def test_run_bad_controller(name, data, needle, write, tmp_path, capsys):
    path = write(name, data) if data is not None else tmp_path / name
    res = run_cli(capsys, "run", path, "--map", FIRE_MAP, "--out", tmp_path / "out")
    assert_no_crash(res)
    assert res.code == 1 and needle in res.err, res.err


@pytest.mark.parametrize("name,data", [("missing.json", None), ("bad.json", '{"bad json'),
                                       ("empty.json", ""), ("list.json", "[1, 2]")])
def test_run_bad_map(name, data, controller_module, write, tmp_path, capsys):
    path = write(name, data) if data is not None else tmp_path / name
    res = run_cli(capsys, "run", controller_module, "--map", path, "--out", tmp_path / "out")
    assert_no_crash(res)
    assert res.code == 1 and name in res.err, res.err


def test_run_binary_map(controller_module, write, tmp_path, capsys):
    path = write("garbage.json", GARBAGE)
    res = run_cli(capsys, "run", controller_module, "--map", path, "--out", tmp_path / "out")
    assert_no_crash(res)
    assert res.code == 1


def test_run_bad_wind_is_usage(controller_module, tmp_path, capsys):
    res = run_cli(capsys, "run", controller_module, "--map", FIRE_MAP, "--wind", "abc",
                  "--out", tmp_path / "out")
    assert_no_crash(res)
    assert res.code == 2


# --- conformance / experiment -----------------------------------------------------------------

def test_conformance_missing_corpus(tmp_path, capsys):
    res = run_cli(capsys, "conformance", tmp_path / "nope")
    assert_no_crash(res)
    assert res.code in (1, 2) and "verdicts.tsv" in res.err


@pytest.mark.parametrize("argv", [["--sizes", "abc"], ["--seeds", "0"]])
def test_experiment_bad_options(argv, tmp_path, capsys):
    res = run_cli(capsys, "experiment", "fig3a", "--quick", "--out", tmp_path / "exp", *argv)
    assert_no_crash(res)
    assert res.code == 2


# --- the real process ------------------------------------------------------------------------

def _iterc(*argv) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "iterplan_compiler.cli", *map(str, argv)],
                          capture_output=True, text=True, timeout=120)


def test_process_ok_and_bad_input(write):
    proc = _iterc("check", GOLDEN_SPEC)
    assert proc.returncode == 0, proc.stderr
    assert "ok (" in proc.stdout
    spec = write("garbage.lts", GARBAGE)
    proc = _iterc("compile", spec, "-o", spec.with_suffix(".py"))
    assert proc.returncode == 1, proc.stderr
    assert "Traceback" not in proc.stderr and f"{spec}:1:" in proc.stderr
    assert not spec.with_suffix(".py").exists()


def test_process_usage_error():
    proc = _iterc("compile")
    assert proc.returncode == 2
    assert "usage: iterc compile" in proc.stderr and "Traceback" not in proc.stderr
