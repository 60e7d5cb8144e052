"""Shared helpers of the CLI QA tests: run ``iterc`` in-process and check its output contract.

The contract (README "Exit codes"; brief): bad *input* never produces a Python traceback or exit
code 3; errors are printed as ``file:line:col: error[CODE]: message`` (or ``file: error[CODE]:``
when the error is about the file as a whole).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import pytest

from iterplan_compiler import cli

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "examples"
GOLDEN_SPEC = REPO / "tests" / "data" / "golden" / "patrol.lts"
CORPUS = REPO.parent / "shared" / "conformance" / "mtsa"

#: One rendered diagnostic head line: file, optional line:col, severity, code.
DIAG_RE = re.compile(
    r"^(?P<file>[^\s:][^:]*?)(?::(?P<line>\d+):(?P<col>\d+))?: "
    r"(?P<sev>error|warning)\[(?P<code>[A-Z]+\d+)\]: (?P<msg>.+)$",
    re.MULTILINE,
)


@dataclass(frozen=True)
class Result:
    """What one ``iterc`` invocation did."""

    code: int
    out: str
    err: str

    def diagnostics(self, severity: str = "error") -> list[re.Match[str]]:
        """The diagnostic head lines of ``severity`` on stderr."""
        return [m for m in DIAG_RE.finditer(self.err) if m["sev"] == severity]


def run_cli(capsys: pytest.CaptureFixture[str], *argv: str | Path) -> Result:
    """Run ``iterc argv...`` in-process; argparse's ``SystemExit`` becomes an exit code."""
    capsys.readouterr()  # drop anything printed before
    try:
        code = cli.main([str(a) for a in argv])
    except SystemExit as exc:  # argparse: --help (0) and usage errors (2)
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    captured = capsys.readouterr()
    return Result(code, captured.out, captured.err)


def assert_no_crash(result: Result) -> None:
    """The user never sees a traceback or the internal-error exit code."""
    text = result.out + result.err
    assert result.code != cli.EXIT_INTERNAL, text
    assert "Traceback (most recent call last)" not in text, text
    assert "internal error" not in text, text


def assert_input_error(result: Result, path: str | Path, *, code: str | None = None,
                       located: bool = False) -> re.Match[str]:
    """Exit 1 with at least one error diagnostic about ``path`` (with line:col if ``located``,
    of ``code`` if given); returns the first matching diagnostic."""
    assert_no_crash(result)
    assert result.code == cli.EXIT_FAIL, (result.code, result.err)
    for m in result.diagnostics():
        if m["file"] != str(path):
            continue
        if located and m["line"] is None:
            continue
        if code is not None and m["code"] != code:
            continue
        if located:
            assert int(m["line"]) >= 1 and int(m["col"]) >= 1
        return m
    raise AssertionError(f"no error diagnostic for {path} (code={code}, located={located}) "
                         f"in:\n{result.err}")

FIRE_MAP = EXAMPLES / "fire_patrol.json"
