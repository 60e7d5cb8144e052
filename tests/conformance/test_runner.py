"""The conformance runner's own machinery: TSV rows, verdict families, baseline ratchet."""

from __future__ import annotations

from pathlib import Path

from iterplan_compiler import conformance as conf


def _row(file="A/x.lts", expected="compiles", composite="C", keywords="", checks=""):
    return conf.Row(file, expected, composite, keywords, checks)


def test_composite_name_takes_first_word():
    assert _row(composite="B (fallback: first composite in Java Hashtable order)"
                ).composite_name == "B"
    assert _row(composite="DEFAULT(all processes)").composite_name == "DEFAULT"
    assert _row(composite="").composite_name == "C"


def test_verdict_families():
    assert _row(expected="realizable (implied)").kind == "realizable"
    assert _row(expected="unrealizable").kind == "unrealizable"
    assert _row(expected="compiles (errors only printed, never fail)").kind == "compiles"
    assert _row(expected="error: recursive composition").kind == "recursion"
    assert _row(expected="not legal").kind == "not legal"
    assert _row(expected="legal").kind == "legal"
    assert _row(expected="n.a. (no synthesis)", checks="strong bisimulation").kind == "bisimilar"


def test_expected_alphabet_parsed_as_a_set():
    checks = "composition alphabet array equals, in this order: [s -1 pressed] (order ...)"
    assert conf._expected_alphabet(checks) == {"s", "-1", "pressed"}
    assert conf._expected_alphabet("no list here") is None


def test_read_rows_skips_header(tmp_path: Path):
    (tmp_path / "verdicts.tsv").write_text(
        "file\texpected\tcomposite\tkeywords\tchecks\n"
        "a.lts\tcompiles\tC\tplain composite\t\n"
        "b.lts\tunrealizable\tC\theuristic\n", encoding="utf-8")
    rows = conf.read_rows(tmp_path)
    assert [r.file for r in rows] == ["a.lts", "b.lts"]
    assert rows[1].checks == ""


def test_baseline_ratchet(tmp_path: Path):
    results = [conf.RowResult("a.lts", "compiles", "pass", "", 0.1),
               conf.RowResult("b.lts", "compiles", "error", "x", 0.1)]
    path = tmp_path / "baseline.tsv"
    conf.write_baseline(path, results)
    base = conf.read_baseline(path)
    assert base == {"a.lts": "pass", "b.lts": "error"}
    assert conf.regressions(results, base) == []
    worse = [conf.RowResult("a.lts", "compiles", "crash", "boom", 0.1), results[1]]
    assert [r.file for r in conf.regressions(worse, base)] == ["a.lts"]


def test_summary_counts_every_status():
    results = [conf.RowResult("a", "compiles", "pass", "", 1.0),
               conf.RowResult("b", "compiles", "timeout", "", 2.0),
               conf.RowResult("c", "realizable", "fail", "", 0.5)]
    table = conf.summary_table(results)
    all_line = next(line for line in table.splitlines() if line.startswith("all"))
    assert all_line.split()[1:] == ["1", "1", "0", "0", "0", "1", "3"]


def test_isolated_run_reports_rows_not_in_the_table(tmp_path: Path):
    (tmp_path / "verdicts.tsv").write_text("file\texpected\tcomposite\tkeywords\tchecks\n",
                                           encoding="utf-8")
    res = conf._run_isolated(tmp_path, _row(file="nope.lts"), timeout=60)
    assert res.status == "error" and "not in verdicts.tsv" in res.detail


def _corpus(tmp_path: Path) -> Path:
    (tmp_path / "ok.lts").write_text("A = (a -> b -> A).\n||C = (A).\n", encoding="utf-8")
    (tmp_path / "bad.lts").write_text("A = (a -> B).\n||C = (A || Missing).\n",
                                      encoding="utf-8")
    (tmp_path / "rec.lts").write_text("||C = (D).\n||D = (C).\n", encoding="utf-8")
    (tmp_path / "alpha.lts").write_text("A = (a -> b -> A)\\{b}.\n||C = (A).\n",
                                        encoding="utf-8")
    (tmp_path / "verdicts.tsv").write_text(
        "file\texpected\tcomposite\tkeywords\tchecks\n"
        "ok.lts\tcompiles\tC\tplain composite\t\n"
        "bad.lts\tcompiles\tC\tplain composite\t\n"
        "rec.lts\terror: recursive composition\tC\tplain composite\t\n"
        "alpha.lts\talphabet check\tC\tplain composite\tequals, in this order: [a] (x)\n",
        encoding="utf-8")
    return tmp_path


def test_corpus_run_gives_each_row_its_status(tmp_path: Path):
    root = _corpus(tmp_path)
    seen = []
    results = conf.run_corpus(root, conf.read_rows(root), jobs=2, timeout=60,
                              on_result=seen.append)
    status = {r.file: r.status for r in results}
    assert status == {"ok.lts": "pass", "bad.lts": "error", "rec.lts": "pass",
                      "alpha.lts": "pass"}
    assert [r.file for r in results] == ["ok.lts", "bad.lts", "rec.lts", "alpha.lts"]
    assert len(seen) == 4


def test_exhausted_budget_reports_timeouts_without_running(tmp_path: Path):
    root = _corpus(tmp_path)
    results = conf.run_corpus(root, conf.read_rows(root), jobs=1, timeout=60, budget=-1)
    assert {r.status for r in results} == {"timeout"}
    assert all(r.detail == "budget exhausted" for r in results)
