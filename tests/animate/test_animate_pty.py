"""``iterc animate`` once through a real pseudo-terminal (prompt_toolkit's prompt)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

pexpect = pytest.importorskip("pexpect", reason="pexpect (test extra) drives the terminal")
pytest.importorskip("prompt_toolkit")

REPO = Path(__file__).resolve().parents[2]
COVER = REPO / "examples" / "cover.lts"


def test_interactive_session(tmp_path):
    saved = tmp_path / "trace.txt"
    # no cursor-position requests: pexpect's terminal does not answer them
    env = dict(os.environ, TERM="xterm", PROMPT_TOOLKIT_NO_CPR="1")
    child = pexpect.spawn(sys.executable, ["-m", "iterplan_compiler", "animate", str(COVER),
                                           "Cover"],
                          env=env, encoding="utf-8", timeout=60, dimensions=(40, 120),
                          cwd=str(tmp_path))
    try:
        child.expect(r"enabled actions \(\* = controllable")
        child.expect(r"1  takeoff \*")
        child.expect("animate>")
        child.sendline("1")                       # by number
        child.expect(r"trace \(1\): takeoff")
        child.expect("animate>")
        child.sendline("takeoff.ended")           # by name
        child.expect(r"trace \(2\): takeoff takeoff.ended")
        child.expect("animate>")
        child.sendline("nosuch")
        child.expect("error: 'nosuch' is not an action of Cover")
        child.expect("animate>")
        child.sendline("undo")
        child.expect("undone")
        child.expect(r"trace \(1\): takeoff")
        child.expect("animate>")
        child.sendline(f"save {saved}")
        child.expect("saved 1 action to")
        child.expect("animate>")
        child.sendline("quit")
        child.expect(pexpect.EOF)
    finally:
        child.close(force=True)
    assert child.exitstatus == 0
    assert saved.read_text() == "takeoff\n"
