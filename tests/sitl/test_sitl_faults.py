"""Faults against real ArduPlane SITL, each asserting the outcome: a pilot's mode change, link
loss (SITL killed), GPS loss (SIM_GPS_DISABLE), Ctrl-C, and a vehicle that never gets ready."""

from tests.sitl.harness import commands, describe, fault_injected, loiter_over, run_scenario


def scenario(controllers, tmp_path, fault, **kw):
    ctl, mp = controllers["fire_patrol"]
    res = run_scenario(tmp_path, controller=ctl, map=mp, fault=fault, **kw)
    assert fault_injected(res), res.get("fault_missed", "no fault_t") + "\n" + describe(res)
    return res


def test_pilot_switches_to_rtl(controllers, tmp_path):
    res = scenario(controllers, tmp_path, "pilot_rtl", fault_after=40)
    s = res["summary"]
    assert res["rc"] == 1 and s["reason"].startswith("mode_changed"), describe(res)
    assert "RTL" in s["reason"] and s["safe_state"].startswith("no command"), describe(res)
    # Stopped commanding within 1 s (vehicle time) of the switch; logs written.
    last = max(t for t, _ in commands(res))
    fault_t = res["fault_t"]
    assert last <= fault_t + 1.0, (last, fault_t)
    assert res["fault_to_exit_wall"] < 10
    assert res["events.csv"] and res["track.csv"]
    # The pilot's RTL stays in force: the runtime never re-entered GUIDED.
    assert res["after"] and {a[1] for a in res["after"]} == {"RTL"}


def test_link_loss_when_sitl_dies(controllers, tmp_path):
    res = scenario(controllers, tmp_path, "kill_sitl", fault_after=30)
    s = res["summary"]
    assert res["rc"] == 1 and s["reason"].startswith("link_lost"), describe(res)
    assert s["safe_state"].startswith("no command"), describe(res)
    assert res["fault_to_exit_wall"] < 15, describe(res)
    assert res["events.csv"].count("\n") > 10


def test_gps_loss_mid_mission(controllers, tmp_path):
    res = scenario(controllers, tmp_path, "gps_off", fault_after=30)
    s = res["summary"]
    assert res["rc"] == 1 and s["reason"].startswith("gps_lost"), describe(res)
    assert s["safe_state"].startswith("rtl commanded; vehicle in RTL"), describe(res)
    assert res["fault_to_exit_wall"] < 10
    assert res["after"] and {a[1] for a in res["after"]} == {"RTL"}


def test_ctrl_c_mid_mission(controllers, tmp_path):
    res = scenario(controllers, tmp_path, "sigint", fault_after=30)
    assert res["iterc_ignores_sigint"] is False, "iterc was started with SIGINT ignored"
    s = res["summary"]
    assert res["rc"] == 1 and s["reason"] == "interrupted", describe(res)
    assert s["safe_state"] == "loiter commanded; vehicle in GUIDED", describe(res)
    assert res["events.csv"] and res["track.csv"] and res["commands.csv"]
    ok, why = loiter_over(res["after"], res["map_centre"], 80.0)
    assert ok, why


def test_vehicle_never_ready(controllers, tmp_path):
    """No GPS from boot: the run waits (bounded), names what is missing, arms nothing."""
    parm = tmp_path / "nogps.parm"
    tmp_path.mkdir(parents=True, exist_ok=True)
    parm.write_text("SIM_GPS_DISABLE 1\n")
    ctl, mp = controllers["fire_patrol"]
    res = run_scenario(tmp_path, controller=ctl, map=mp, params=[str(parm)],
                       args=["--ready-timeout", "15"], watch_after=5)
    assert res["rc"] == 1, describe(res)
    assert "vehicle not ready after 15 s" in res["stdout"] + res["stderr"], describe(res)
    assert "3-D GPS fix" in res["stderr"]
    assert res["after"] and not any(a[2] for a in res["after"])          # never armed
