"""The live view in a real browser: headless Chromium (Debian's chromium + chromium-driver)
driven by Selenium watches ``iterc run --view`` fly the Fire Patrol example.

Skips with a reason when selenium, the view's dependencies, chromium or chromedriver are
missing (``.ci/run`` installs them).  Screenshots go to ``$ITERPLAN_ARTEFACTS`` (default
``test-artefacts/`` in the repository): ``view-live.png`` mid-flight, ``view-final.png``,
``view-replay.png`` (``iterc view``).
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
ARTEFACTS = Path(os.environ.get("ITERPLAN_ARTEFACTS", ROOT / "test-artefacts"))


def _find(*names: str) -> str | None:
    for n in names:
        p = shutil.which(n)
        if p:
            return p
    return None


def _browser():
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        pytest.skip("selenium is not installed (pip install 'iterplan[view-test]')")
    from iterplan_compiler.view import missing_dependency
    if missing_dependency():
        pytest.skip(missing_dependency())
    chrome = _find("chromium", "chromium-browser", "google-chrome")
    driver = _find("chromedriver")
    if chrome is None or driver is None:
        pytest.skip("no browser: apt-get install chromium chromium-driver")
    opts = webdriver.ChromeOptions()
    opts.binary_location = chrome
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
              "--window-size=1280,800", "--disable-extensions", "--no-first-run"):
        opts.add_argument(a)
    try:
        return webdriver.Chrome(service=Service(driver), options=opts)
    except Exception as exc:  # noqa: BLE001 - a broken browser install is a skip, not a failure
        pytest.skip(f"chromium did not start: {str(exc).splitlines()[0]}")


def _until(pred, timeout: float, what: str, poll: float = 0.25):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        v = pred()
        if v:
            return v
        time.sleep(poll)
    raise AssertionError(f"timed out after {timeout:.0f} s waiting for {what}")


def test_live_view_in_chromium(tmp_path):
    browser = _browser()
    ctl = tmp_path / "fire_patrol_ctl.py"
    shutil.copy(ROOT / "tests" / "runtime" / "fire_patrol.py", ctl)
    out = tmp_path / "out"
    # ~120 simulated seconds at 3x: about 40 s of wall time to watch.
    proc = subprocess.Popen(
        [sys.executable, "-m", "iterplan_compiler", "run", str(ctl), "--map",
         str(ROOT / "examples" / "fire_patrol.json"), "--out", str(out), "--no-plot",
         "--quiet", "--view", "127.0.0.1:0", "--realtime", "3", "--view-linger", "300"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    try:
        line = proc.stdout.readline()
        m = re.search(r"live view: (http://\S+)", line)
        assert m, f"no view URL printed: {line!r} {proc.stderr.read() if proc.poll() else ''}"
        url = m.group(1)
        browser.get(url)
        text = lambda i: browser.find_element("id", i).text  # noqa: E731

        def marker():
            els = browser.find_elements("css selector", ".aircraft-icon")
            return els[0].get_attribute("style") if els else None

        _until(lambda: marker() and text("ctrl-state").startswith("state"), 60,
               "the aircraft and the controller state on the page")
        first_style, first_state = marker(), text("ctrl-state")
        first_done = int(text("done-count") or 0)
        seen = {"moved": False, "states": {first_state}, "done": False}

        def flying_and(check):
            """Observe while the mission flies: the page must not say it completed yet."""
            def pred():
                ok = check()
                assert "mission completed" not in text("status"), \
                    f"mission completed before the page showed {check.__doc__}"
                return ok
            return pred

        def moved():
            """the aircraft marker moving"""
            return marker() != first_style

        def state_changed():
            """the controller state changing"""
            seen["states"].add(text("ctrl-state"))
            return len(seen["states"]) > 1

        def done_grew():
            """|D| increasing"""
            return int(text("done-count") or 0) > first_done

        for check in (moved, state_changed, done_grew):
            _until(flying_and(check), 90, check.__doc__)
        ARTEFACTS.mkdir(parents=True, exist_ok=True)
        browser.save_screenshot(str(ARTEFACTS / "view-live.png"))
        _until(lambda: "mission completed" in text("status"), 180, '"mission completed"')
        assert int(text("done-count")) > first_done
        assert text("next").startswith("null")      # one full pass: n is null at the end
        browser.save_screenshot(str(ARTEFACTS / "view-final.png"))
        assert (ARTEFACTS / "view-final.png").stat().st_size > 10_000
        assert (out / "summary.json").is_file()     # outputs written before lingering
    finally:
        browser.quit()
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
        try:
            rc = proc.wait(30)
        except subprocess.TimeoutExpired:
            proc.kill()
            rc = proc.wait()
        proc.stdout.close()
        proc.stderr.close()
    assert rc == 0


def test_replay_in_chromium(tmp_path):
    """``iterc view RUN_DIR``: the slider moves the page through the finished run."""
    browser = _browser()
    from iterplan_compiler.cli import main

    ctl = tmp_path / "fire_patrol_ctl.py"
    shutil.copy(ROOT / "tests" / "runtime" / "fire_patrol.py", ctl)
    fire_map = str(ROOT / "examples" / "fire_patrol.json")
    out = tmp_path / "out"
    assert main(["run", str(ctl), "--map", fire_map, "--out", str(out), "--quiet", "--no-plot",
                 "--ideal-compute"]) == 0
    proc = subprocess.Popen([sys.executable, "-m", "iterplan_compiler", "view", str(out),
                             "--map", fire_map, "--linger", "120"],
                            stdout=subprocess.PIPE, text=True, cwd=tmp_path)
    try:
        url = proc.stdout.readline().split()[2]
        browser.get(url)
        text = lambda i: browser.find_element("id", i).text  # noqa: E731
        _until(lambda: "mission completed" in text("status"), 60, "the replay's end state")
        assert text("done-count") == "64" and text("visits").startswith("9 / 2")
        browser.execute_script(
            "var s = document.getElementById('slider'); s.value = 30;"
            "s.dispatchEvent(new Event('input'));")
        _until(lambda: text("status").startswith("replay at"), 30, "the slider's time")
        assert 0 < int(text("done-count")) < 64
        assert text("ctrl-state").startswith("state")
        ARTEFACTS.mkdir(parents=True, exist_ok=True)
        browser.save_screenshot(str(ARTEFACTS / "view-replay.png"))
    finally:
        browser.quit()
        proc.terminate()
        rc = proc.wait(30)
        proc.stdout.close()
    assert rc == 0
