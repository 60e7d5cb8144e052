"""Outputs (issue 14): atomic writes, no overwriting an input, experiments that append and
resume -- and a kill -9 at every write point leaves the old content intact or the new one
complete, never a 0-byte or partial file."""

from __future__ import annotations

import csv
import os
import subprocess
import sys
from pathlib import Path

import pytest

from iterplan_compiler import cli, outputs

REPO = Path(__file__).resolve().parents[2]
FIRE = REPO / "examples" / "fire_patrol.lts"
WRITE_POINTS = ["mid-write", "before-replace", "after-replace"]


def _py(code: str, env_kill: str | None, cwd: Path) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != outputs.KILL_ENV}
    if env_kill:
        env[outputs.KILL_ENV] = env_kill
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=120)


def _iterc(args: list[str], env_kill: str | None, cwd: Path) -> subprocess.CompletedProcess:
    code = ("import sys; from iterplan_compiler import cli; "
            f"sys.exit(cli.main({args!r}))")
    return _py(code, env_kill, cwd)


# ------------------------------------------------------------------ unit behaviour


def test_atomic_write_replaces_and_leaves_no_temp_file(tmp_path):
    p = tmp_path / "a.txt"
    p.write_text("old")
    os.chmod(p, 0o640)
    outputs.atomic_write_text(p, "new content\n")
    assert p.read_text() == "new content\n"
    assert (p.stat().st_mode & 0o777) == 0o640  # permissions kept
    assert sorted(x.name for x in tmp_path.iterdir()) == ["a.txt"]


def test_atomic_write_to_a_missing_folder_raises_oserror(tmp_path):
    with pytest.raises(OSError):
        outputs.atomic_write_bytes(tmp_path / "no" / "a.bin", b"x")


def test_refuse_overwrite_input_sees_through_paths_and_links(tmp_path, monkeypatch):
    spec = tmp_path / "x.lts"
    spec.write_text("A = (a -> A).\n")
    link = tmp_path / "link.lts"
    link.symlink_to(spec)
    monkeypatch.chdir(tmp_path)
    for out in ("x.lts", "./x.lts", str(spec), "link.lts"):
        with pytest.raises(outputs.OutputError, match="refusing to overwrite the input"):
            outputs.refuse_overwrite_input(out, ["x.lts"])
    outputs.refuse_overwrite_input("y.py", ["x.lts"])  # a new file is fine
    outputs.refuse_overwrite_input(None, ["x.lts"])


def test_append_line_and_complete_lines_drop_a_torn_last_line(tmp_path):
    p = tmp_path / "log.csv"
    outputs.append_line(p, "a,b")
    outputs.append_line(p, "1,2")
    with open(p, "ab") as f:
        f.write(b"3,")  # a write that was killed half-way
    assert outputs.complete_lines(p) == ["a,b", "1,2"]
    outputs.append_line(p, "4,5")
    assert p.read_text() == "a,b\n1,2\n4,5\n"


def test_check_writable_dir(tmp_path):
    outputs.check_writable_dir(tmp_path / "new" / "dir")
    (tmp_path / "file").write_text("")
    with pytest.raises(outputs.OutputError):
        outputs.check_writable_dir(tmp_path / "file")


# ------------------------------------------------------------------ iterc compile / dot


def test_compile_refuses_to_overwrite_its_spec(tmp_path, capsys):
    spec = tmp_path / "x.lts"
    spec.write_text(FIRE.read_text())
    before = spec.read_bytes()
    assert cli.main(["compile", str(spec), "-o", str(spec)]) == 1
    assert "refusing to overwrite the input" in capsys.readouterr().err
    assert spec.read_bytes() == before


def test_compile_refuses_to_overwrite_an_included_file(tmp_path, capsys):
    (tmp_path / "lib.lts").write_text("set Acts = {a, b}\n")
    spec = tmp_path / "x.lts"
    spec.write_text('include "lib.lts"\nA = (a -> b -> A).\n||C = (A).\n')
    before = (tmp_path / "lib.lts").read_bytes()
    rc = cli.main(["dot", str(spec), "C", "-o", str(tmp_path / "lib.lts")])
    assert rc == 2 or rc == 1  # .lts is not a drawing suffix: usage error first
    rc = cli.main(["compile", str(spec), "-o", str(tmp_path / "lib.lts"), "--emit", "fsp"])
    assert rc == 1
    assert (tmp_path / "lib.lts").read_bytes() == before


def test_dot_refuses_to_overwrite_its_spec(tmp_path, capsys):
    spec = tmp_path / "x.dot"  # a spec file that happens to be called .dot
    spec.write_text("A = (a -> A).\n")
    assert cli.main(["dot", str(spec), "A", "-o", str(spec)]) == 1
    assert "refusing to overwrite the input" in capsys.readouterr().err
    assert spec.read_text() == "A = (a -> A).\n"


@pytest.fixture(scope="module")
def compiled_text(tmp_path_factory) -> str:
    d = tmp_path_factory.mktemp("ref")
    r = _iterc(["compile", str(FIRE), "-o", str(d / "ref.py")], None, d)
    assert r.returncode == 0, r.stderr
    return (d / "ref.py").read_text()


@pytest.mark.parametrize("point", WRITE_POINTS)
def test_kill_during_compile_output_keeps_old_or_complete_new(point, tmp_path, compiled_text):
    out = tmp_path / "ctl.py"
    out.write_text("OLD CONTENT\n")
    r = _iterc(["compile", str(FIRE), "-o", str(out)], point, tmp_path)
    assert r.returncode == -9, (r.returncode, r.stderr)
    text = out.read_text()
    if point == "after-replace":
        assert text == compiled_text
    else:
        assert text == "OLD CONTENT\n"


@pytest.mark.parametrize("point", WRITE_POINTS)
def test_kill_during_dot_output_keeps_old_or_complete_new(point, tmp_path):
    out = tmp_path / "fire.dot"
    out.write_text("digraph old {}\n")
    r = _iterc(["dot", str(FIRE), "Iterator", "-o", str(out)], point, tmp_path)
    assert r.returncode == -9, (r.returncode, r.stderr)
    text = out.read_text()
    assert text == "digraph old {}\n" if point != "after-replace" else \
        text.startswith("digraph") and text.rstrip().endswith("}")


@pytest.mark.parametrize("point", [*WRITE_POINTS, "mid-append", "after-append"])
def test_kill_at_every_library_write_point(point, tmp_path):
    p = tmp_path / "f.txt"
    p.write_text("old\n")
    new = "new line\n" * 10_000
    code = ("from iterplan_compiler import outputs\n"
            f"outputs.atomic_write_text({str(p)!r}, {new!r})\n"
            f"outputs.append_line({str(p)!r}, 'appended')\n")
    r = _py(code, point, tmp_path)
    assert r.returncode == -9, r.stderr
    data = p.read_bytes()
    assert data, "0-byte file"
    if point in ("mid-write", "before-replace"):
        assert data == b"old\n"
    elif point == "after-replace":
        assert data.decode() == new
    else:  # appended logs: complete lines only once read back
        lines = outputs.complete_lines(p)
        assert lines[: 10_000] == ["new line"] * 10_000
        assert lines[10_000:] in ([], ["appended"])


# ------------------------------------------------------------------ iterc experiment


EXP = ["experiment", "fig3c", "--quick", "--seeds", "1", "--sorters", "last",
       "--no-progress", "--out"]


def test_experiment_killed_mid_sweep_resumes_from_its_appended_rows(tmp_path):
    out = tmp_path / "exp"
    # killed while appending the 2nd finished run: the 1st row is safe, the 2nd torn
    r = _iterc([*EXP, str(out)], "mid-append:2", tmp_path)
    assert r.returncode == -9, r.stderr
    partial = out / "fig3c.partial.csv"
    lines = outputs.complete_lines(partial)
    assert len(lines) == 2  # header + one complete row
    assert not (out / "fig3c.csv").exists()
    r = _iterc([*EXP, str(out)], None, tmp_path)
    assert r.returncode == 0, r.stderr
    assert "resuming: 1 of" in r.stderr
    assert not partial.exists()
    rows = list(csv.DictReader((out / "fig3c.csv").open()))
    assert len(rows) >= 2 and all(not row["error"] for row in rows)
    assert len({(row["count"], row["seed"]) for row in rows}) == len(rows)


# ------------------------------------------------------------------ a run's output folder


def test_output_folder_publishes_all_files_together(tmp_path):
    target = tmp_path / "run"
    target.mkdir()
    (target / "summary.json").write_text('{"old": true}')
    with outputs.OutputFolder(target) as out:
        out.write_text("track.geojson", '{"type": "FeatureCollection", "features": []}')
        out.write_text("summary.json", '{"new": true}')
        assert (target / "summary.json").read_text() == '{"old": true}'  # not yet
    assert sorted(p.name for p in target.iterdir()) == ["summary.json", "track.geojson"]
    assert (target / "summary.json").read_text() == '{"new": true}'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def test_output_folder_of_a_failed_run_is_marked_partial(tmp_path):
    target = tmp_path / "run"
    target.mkdir()
    (target / "summary.json").write_text("old")
    with pytest.raises(RuntimeError), outputs.OutputFolder(target) as out:
        out.write_text("track.csv", "t,x\n")
        raise RuntimeError("the vehicle link dropped")
    assert (target / "summary.json").read_text() == "old"  # the previous run is intact
    partial = tmp_path / "run.partial"
    assert (partial / "track.csv").read_text() == "t,x\n"
    assert "vehicle link dropped" in (partial / outputs.PARTIAL_MARKER).read_text()


@pytest.mark.parametrize("point", ["after-replace:2", "between-folders"])
def test_kill_during_a_run_never_mixes_old_and_new_outputs(point, tmp_path):
    target = tmp_path / "run"
    target.mkdir()
    (target / "summary.json").write_text("old summary")
    (target / "track.csv").write_text("old track")
    code = ("from iterplan_compiler import outputs\n"
            f"with outputs.OutputFolder({str(target)!r}) as out:\n"
            "    out.write_text('track.csv', 'new track')\n"
            "    out.write_text('summary.json', 'new summary')\n")
    r = _py(code, point, tmp_path)
    assert r.returncode == -9, r.stderr
    if target.exists():  # the old run, whole
        assert {p.name: p.read_text() for p in target.iterdir()} == \
            {"summary.json": "old summary", "track.csv": "old track"}
    else:  # killed between the two renames: the old run is kept aside, whole
        (old,) = tmp_path.glob(".run.previous-*")
        assert (old / "summary.json").read_text() == "old summary"
    (staged,) = tmp_path.glob(".run.staging-*")
    if point == "between-folders":  # the new run was complete, only not yet published
        assert {p.name: p.read_text() for p in staged.iterdir()} == \
            {"summary.json": "new summary", "track.csv": "new track"}
    else:  # still running: marked as such
        assert (staged / outputs.PARTIAL_MARKER).exists()


def test_atomic_write_json_never_writes_invalid_json(tmp_path):
    import json
    import math

    p = tmp_path / "track.geojson"
    p.write_text('{"type": "FeatureCollection", "features": []}')
    with pytest.raises(ValueError):
        outputs.atomic_write_json(p, {"type": "Point", "coordinates": [math.nan, 1.0]})
    json.loads(p.read_text())  # the old, valid file is still there
    outputs.atomic_write_json(p, {"type": "Point", "coordinates": [149.1, -35.3]})
    assert json.loads(p.read_text())["coordinates"] == [149.1, -35.3]
