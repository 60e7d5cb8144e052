"""``iterc verify`` against a stand-in model (the real front-end is exercised in
test_fltl_verify_specs.py once it is available)."""

from dataclasses import dataclass, field

import pytest
from fltl_helpers import act, fl

from iterplan_compiler import cli, pipeline
from iterplan_compiler.ir.formulas import Always, Eventually, FluentProp, Implies, NamedFormula
from iterplan_compiler.ir.lts import make_lts


@dataclass
class FakeModel:
    lts: dict
    formulas: dict
    fluents: dict = field(default_factory=dict)
    source_path: str = "spec.lts"
    source_text: str = ""

    def names(self):
        return tuple(self.lts)

    def build_lts(self, name, unrealizable="error", solve=True):
        return self.lts[name], []


@pytest.fixture
def spec(tmp_path, monkeypatch):
    path = tmp_path / "spec.lts"
    path.write_text("// stand-in\n")
    sys_ = make_lts("Sys", 2, [(0, "a", 1), (1, "b", 0), (1, "c", 1)])
    model = FakeModel(
        {"Sys": sys_},
        {
            "Resp": NamedFormula("Resp", "assert", Always(Implies(act("a"), Eventually(act("b"))))),
            "Safe": NamedFormula("Safe", "assert", Always(Implies(act("c"), FluentProp("On")))),
            "Bad": NamedFormula("Bad", "assert", FluentProp("Missing")),
        },
        {"On": fl("On", {"a"}, {"b"})},
    )
    monkeypatch.setattr(pipeline, "load",
                        lambda p, text=None: pipeline.Elaborated(str(p), model, (), {}))
    return str(path)


def test_verify_holds(spec, capsys):
    assert cli.main(["verify", spec, "--assert", "Safe", "--on", "Sys"]) == 0
    assert "No LTL Property violations detected" in capsys.readouterr().out


def test_verify_prints_lasso_counterexample(spec, capsys):
    # Under fair choice b is eventually taken in state 1, so Resp holds ...
    assert cli.main(["verify", spec, "--assert", "Resp", "--on", "Sys"]) == 0
    capsys.readouterr()
    # ... but not on every run: the c self-loop starves it.
    assert cli.main(["verify", spec, "--assert", "Safe", "--assert", "Resp", "--on", "Sys",
                     "--unfair"]) == 1
    out = capsys.readouterr().out
    assert "assert Safe on Sys: No LTL Property violations detected" in out
    assert "Violation of LTL property Resp" in out
    assert "Cycle in terminal set:\n    c" in out


def test_verify_reports_bad_names(spec, capsys):
    assert cli.main(["verify", spec, "--assert", "Rsp", "--on", "Sys"]) == 1
    err = capsys.readouterr().err
    assert "E0607" in err and "did you mean 'Resp'" in err
    assert cli.main(["verify", spec, "--assert", "Resp", "--on", "Nope"]) == 1
    assert "E0608" in capsys.readouterr().err
    assert cli.main(["verify", spec, "--assert", "Bad", "--on", "Sys"]) == 1
    assert "E0604" in capsys.readouterr().err


def test_verify_usage(spec, capsys):
    # Missing --on is a usage error (argparse exits 2).
    with pytest.raises(SystemExit) as exc:
        cli.main(["verify", spec, "--assert", "Resp"])
    assert exc.value.code == 2
    assert "--on" in capsys.readouterr().err


def test_verify_missing_file_is_an_input_error(tmp_path, capsys):
    # The real front-end (not the stand-in): an unreadable SPEC is E0800, exit 1, as in `check`.
    missing = tmp_path / "nope.lts"
    assert cli.main(["verify", str(missing), "--assert", "Resp", "--on", "Sys"]) == 1
    assert f"{missing}: error[E0800]: cannot read" in capsys.readouterr().err
