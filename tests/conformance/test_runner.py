"""The conformance runner's own machinery: TSV rows, verdict families, planned checks, strict
statuses, the per-row baseline ratchet."""

from __future__ import annotations

from pathlib import Path

import pytest

from iterplan_compiler import conformance as conf
from iterplan_compiler import conformance_checks as cc

EVERY = "every composite compiles+composes without LTSException; other exceptions/timeouts are swallowed"


def _row(file="A/x.lts", expected="compiles", composite="C", keywords="", checks=EVERY):
    return conf.Row(file, expected, composite, keywords, checks)


def _res(key, status, kind="compiles"):
    return conf.RowResult(key.partition("::")[0], key, kind, status, "", 0.1)


def test_composite_column_lists_every_composite():
    assert _row(composite="B (fallback: first composite in Java Hashtable order)"
                ).composites == ("B",)
    assert _row(composite="DEFAULT(all processes)").composites == ("DEFAULT",)
    assert _row(composite="TT, BIS, C, Comp").composites == ("TT", "BIS", "C", "Comp")
    assert _row(composite="").composites == ("C",)


def test_rows_sharing_a_file_have_distinct_keys():
    a = _row(file="x.lts", composite="WithAsterisk")
    b = _row(file="x.lts", composite="WithAlphabetSet")
    assert a.key == "x.lts::WithAsterisk" and a.key != b.key


def test_verdict_families():
    F = cc.Family
    assert _row(expected="realizable (implied)").family == F.REALIZABLE
    assert _row(expected="unrealizable").family == F.UNREALIZABLE
    assert _row(expected="compiles (errors only printed, never fail)").family == F.NEVER_FAILS
    assert _row(expected="error: recursive composition").family == F.RECURSION
    assert _row(expected="not legal").family == F.NOT_LEGAL
    assert _row(expected="legal").family == F.LEGAL
    assert _row(expected="n.a. (no synthesis: plain/property composite)").family == F.BISIMILAR
    assert _row(expected="realizable-ish").family == F.UNKNOWN


def test_plan_names_every_clause():
    names = [c.name for c in cc.plan(
        "realizable", ("DirectedController",),
        "composition!=null & ntransitions>0; assert Check holds on ||Sys; "
        "LegalityAnalyser(Sys,'DirectedController','Plant',controllable of Goal) legal")]
    assert names == ["realizable DirectedController", "ntransitions>0 DirectedController",
                     "assert Check on Sys", "legal Sys"]
    names = [c.name for c in cc.plan(
        "realizable", ("WithAsterisk",),
        "WithAsterisk and WithAlphabetSet must agree (both non-null); CheckWith/CheckWithout "
        "hold on SysWith and SysWithout")]
    assert names == ["realizable WithAsterisk", "realizable WithAlphabetSet",
                     "assert CheckWith on SysWith", "assert CheckWithout on SysWithout"]
    assert [c.name for c in cc.plan("compiles", ("TT", "C"), EVERY)] == ["builds TT", "builds C"]


def test_worst_status_wins():
    S = cc.Status
    assert cc.worst([S.PASS, S.UNSUPPORTED, S.PASS]) == S.UNSUPPORTED
    assert cc.worst([S.PASS, S.FAIL, S.UNSUPPORTED]) == S.FAIL
    assert cc.worst([S.ERROR, S.FAIL]) == S.ERROR
    assert cc.worst([]) == S.ERROR


def test_baseline_ratchet_per_row(tmp_path: Path):
    results = [_res("a.lts::X", "pass"), _res("a.lts::Y", "error")]
    path = tmp_path / "baseline.tsv"
    conf.write_baseline(path, results)
    base = conf.read_baseline(path)
    assert base == {"a.lts::X": "pass", "a.lts::Y": "error"}
    assert conf.regressions(results, base) == []
    worse = [_res("a.lts::X", "crash"), results[1]]
    assert [r.key for r in conf.regressions(worse, base)] == ["a.lts::X"]


def test_rewriting_the_baseline_never_drops_a_pass(tmp_path: Path):
    path = tmp_path / "baseline.tsv"
    path.write_text("# old format: file<TAB>status\na.lts\tpass\nb.lts\terror\n",
                    encoding="utf-8")
    old = conf.read_baseline(path)
    assert conf.baseline_status(old, "a.lts::C") == "pass"  # the old key stands for the file
    now = [_res("a.lts::C", "fail"), _res("b.lts::C", "pass")]
    assert [r.key for r in conf.regressions(now, old)] == ["a.lts::C"]
    conf.write_baseline(path, now, keep=old)
    assert conf.read_baseline(path) == {"a.lts::C": "pass", "b.lts::C": "pass"}


def test_summary_counts_every_status():
    results = [_res("a", "pass"), _res("b", "timeout"), _res("c", "fail", kind="realizable")]
    table = conf.summary_table(results)
    all_line = next(line for line in table.splitlines() if line.startswith("all"))
    assert all_line.split()[1:] == ["1", "0", "1", "0", "0", "1", "3"]


def test_isolated_run_reports_rows_not_in_the_table(tmp_path: Path):
    (tmp_path / "verdicts.tsv").write_text("file\texpected\tcomposite\tkeywords\tchecks\n",
                                           encoding="utf-8")
    res = conf._run_isolated(tmp_path, _row(file="nope.lts"), timeout=60)
    assert res.status == "error" and "not in verdicts.tsv" in res.detail


FILES = {
    "ok.lts": "A = (a -> b -> A).\n||C = (A).\n||D = (A).\n",
    "bad.lts": "A = (a -> B).\n||C = (A || Missing).\n",
    "rec.lts": "||C = (D).\n||D = (C).\n",
    "alpha.lts": "A = (a -> b -> A)\\{b}.\n||C = (A).\n",
    "procs.lts": "A = (a -> A).\nB = (b -> B).\n",
    "mts.lts": "A = (a? -> A).\n||C = (A).\n",
    "game.lts": (
        "set Ctrl = {go, stop}\nA = (go -> done -> A | stop -> fail -> A).\n"
        "fluent Done = <done, fail>\nassert Check = []<>Done\nassert CheckAlso = [](!go)\n"
        "controllerSpec G = {liveness = {Done} controllable = {Ctrl}}\n"
        "||Plant = (A).\nheuristic ||DirectedController = (Plant)~{G}.\n"
        "||Sys = (DirectedController || Plant).\n"),
}

ROWS = [
    ("ok.lts", "compiles", "C", EVERY),
    ("ok.lts", "compiles", "C, D", EVERY),
    ("ok.lts", "compiles", "C, Nope", EVERY),
    ("bad.lts", "compiles", "C", EVERY),
    ("rec.lts", "error: recursive composition", "C",
     "LTSException containing 'recursive expression while parallel composing'"),
    ("alpha.lts", "alphabet check", "C", "composition alphabet array equals: [a] (x)"),
    ("procs.lts", "compiles", "DEFAULT(all processes)", EVERY),
    ("mts.lts", "compiles", "C", EVERY),
    ("ok.lts", "realizable-ish", "C", EVERY),
    ("ok.lts", "compiles", "D", "a clause nobody wrote a check for"),
    ("game.lts", "realizable", "DirectedController",
     "composition!=null & ntransitions>0; assert Check holds on ||Sys"),
    ("game.lts", "realizable", "Plant", "composition!=null"),
    ("bad.lts", "compiles (errors only printed, never fail)", "C",
     'MTSCompiler.compileCompositeState("C")'),
    ("mts.lts", "compiles (errors only printed, never fail)", "C",
     'MTSCompiler.compileCompositeState("C")'),
]


def _corpus(tmp_path: Path, rows=ROWS) -> Path:
    for name, text in FILES.items():
        (tmp_path / name).write_text(text, encoding="utf-8")
    lines = ["file\texpected\tcomposite\tkeywords\tchecks"]
    lines += [f"{f}\t{e}\t{c}\tkw\t{k}" for f, e, c, k in rows]
    (tmp_path / "verdicts.tsv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return tmp_path


def _results(tmp_path: Path, rows=ROWS) -> list[conf.RowResult]:
    root = _corpus(tmp_path, rows)
    return [conf.check_row(root, row) for row in conf.read_rows(root)]


def test_strict_statuses(tmp_path: Path):
    got = [(r.key, r.status) for r in _results(tmp_path)]
    assert got == [
        ("ok.lts::C", "pass"),
        ("ok.lts::C", "pass"),
        ("ok.lts::C", "error"),           # a listed composite that does not exist
        ("bad.lts::C", "error"),
        ("rec.lts::C", "pass"),
        ("alpha.lts::C", "pass"),
        ("procs.lts::DEFAULT", "pass"),   # DEFAULT is built, not skipped
        ("mts.lts::C", "unsupported"),    # E0150, the explicit reason
        ("ok.lts::C", "error"),           # unknown verdict family
        ("ok.lts::D", "error"),           # unrecognised check clause
        ("game.lts::DirectedController", "pass"),
        ("game.lts::Plant", "error"),     # not a synthesis composite: no verdict, no pass
        ("bad.lts::C", "pass"),           # MTSA's ParserTests only print errors
        ("mts.lts::C", "unsupported"),    # ... but what we reject on purpose stays unsupported
    ]


def test_row_detail_lists_each_check(tmp_path: Path):
    res = _results(tmp_path)
    two = res[1]
    assert [c.name for c in two.checks] == ["builds C", "builds D"]
    assert "builds C: pass" in two.detail and "builds D: pass" in two.detail
    nope = res[2]
    assert [c.status for c in nope.checks] == [cc.Status.PASS, cc.Status.ERROR]
    assert "no such composite" in nope.checks[1].detail
    game = res[10]
    assert [c.name for c in game.checks] == ["realizable DirectedController",
                                             "ntransitions>0 DirectedController",
                                             "assert Check on Sys"]
    assert all(c.status == cc.Status.PASS for c in game.checks)
    default = res[6]
    assert [c.name for c in default.checks] == ["builds DEFAULT"]
    # (a -> A) || (b -> B): one state, both loops — the composition of every process
    assert default.checks[0].detail == "1 states, 2 transitions"


@pytest.mark.parametrize("formula,status", [("CheckAlso", "fail"), ("Missing", "error")])
def test_every_named_assertion_is_checked(tmp_path: Path, formula, status):
    rows = [("game.lts", "realizable", "DirectedController",
             f"composition!=null; assert Check holds on ||Sys; assert {formula} holds on ||Sys")]
    (res,) = _results(tmp_path, rows)
    assert [c.status.value for c in res.checks] == ["pass", "pass", status]
    assert res.status == status


def test_corpus_run_in_child_processes(tmp_path: Path):
    root = _corpus(tmp_path, ROWS[:6])
    seen = []
    results = conf.run_corpus(root, conf.read_rows(root), jobs=2, timeout=60,
                              on_result=seen.append)
    assert [r.status for r in results] == ["pass", "pass", "error", "error", "pass", "pass"]
    assert all(r.checks for r in results) and len(seen) == 6


def test_exhausted_budget_reports_timeouts_without_running(tmp_path: Path):
    root = _corpus(tmp_path)
    results = conf.run_corpus(root, conf.read_rows(root), jobs=1, timeout=60, budget=-1)
    assert {r.status for r in results} == {"timeout"}
    assert all(r.detail == "budget exhausted" for r in results)


CORPUS = Path(__file__).resolve().parents[3] / "shared" / "conformance" / "mtsa"


@pytest.mark.skipif(not (CORPUS / "verdicts.tsv").is_file(), reason="corpus not present")
def test_every_corpus_row_is_understood():
    rows = conf.read_rows(CORPUS)
    assert len({r.key for r in rows}) == len(rows)
    for row in rows:
        assert row.family != cc.Family.UNKNOWN, row.key
        names = [c.name for c in cc.plan(row.expected, row.composites, row.checks)]
        assert not any(n in ("verdict", "check", "checks") for n in names), (row.key, names)


def test_report_prints_every_row_with_every_check(tmp_path: Path, capsys):
    from iterplan_compiler import cli

    root = _corpus(tmp_path, ROWS[:3])
    code = cli.main(["conformance", str(root), "-j", "1"])
    out = capsys.readouterr().out
    assert code == 0
    lines = [line for line in out.splitlines() if line.startswith("[")]
    assert len(lines) == 3
    assert lines[1].endswith("builds C: pass; builds D: pass")
    assert "builds Nope: error" in lines[2]
    assert "      error       builds Nope: no such composite in the file" in out


def test_a_missing_checker_module_is_never_a_pass(tmp_path: Path, monkeypatch):
    import sys

    rows = [("game.lts", "realizable", "DirectedController",
             "composition!=null; assert Check holds on ||Sys")]
    monkeypatch.setitem(sys.modules, "iterplan_compiler.fltl.check", None)  # import fails
    (res,) = _results(tmp_path, rows)
    assert [c.status.value for c in res.checks] == ["pass", "crash"]
    assert res.status == "crash" and "ModuleNotFoundError" in res.checks[1].detail
