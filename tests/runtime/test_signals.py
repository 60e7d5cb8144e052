"""A mission stays interruptible however it was started (runfiles.sigterm_as_interrupt)."""

import signal
import subprocess
import sys
import time

import pytest

CHILD = """
import sys, time
from iterplan_compiler.runtime.runfiles import sigterm_as_interrupt
with sigterm_as_interrupt():
    try:
        print("ready", flush=True)
        time.sleep(30)
    except KeyboardInterrupt as exc:
        print("interrupted", exc, flush=True)
        sys.exit(3)
"""


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_signal_interrupts_even_when_inherited_ignored(sig):
    # A background job of a non-interactive shell starts with SIGINT ignored.
    proc = subprocess.Popen([sys.executable, "-c", CHILD], stdout=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN))
    assert proc.stdout.readline().strip() == "ready"
    t0 = time.monotonic()
    proc.send_signal(sig)
    out, _ = proc.communicate(timeout=20)
    assert proc.returncode == 3 and "interrupted" in out
    assert time.monotonic() - t0 < 10
