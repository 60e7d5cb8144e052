"""One diagnostic-code registry (``diagnostics.CODES``): every code literal in the compiler is
registered, follows the one scheme, and every registered code is emitted somewhere."""

from __future__ import annotations

import re
from pathlib import Path

from iterplan_compiler import diagnostics
from iterplan_compiler.diagnostics import CODES, Stage

PACKAGE = Path(diagnostics.__file__).resolve().parent
# a quoted code: "E0101", "W0301", "G112" (unquoted words in lint comments are not codes)
LITERAL = re.compile(r"""["']([A-Z]\d{3,4})["']""")
SCHEME = re.compile(r"^(?:[EW]\d{4}|G\d{3})$")
STAGE_OF_HUNDREDS = {0: Stage.INPUT, 1: Stage.NAMES, 2: Stage.EXPRESSIONS, 3: Stage.PROCESSES,
                     4: Stage.COMPOSITION, 5: Stage.FLUENTS, 6: Stage.FORMULAS, 7: Stage.SPECS,
                     8: Stage.FILES, 9: Stage.SYNTHESIS, 10: Stage.EMIT, 13: Stage.LTSA}


def _emitted() -> dict[str, list[str]]:
    found: dict[str, list[str]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.name == "diagnostics.py":
            continue
        for code in LITERAL.findall(path.read_text(encoding="utf-8")):
            found.setdefault(code, []).append(str(path.relative_to(PACKAGE)))
    return found


def test_the_scan_finds_codes():
    found = _emitted()
    # the scan must see the codes of several stages, or the checks below prove nothing
    assert {"E0001", "E0201", "E0402", "E0605", "E0901", "E0104", "G112"} <= set(found)


def test_every_emitted_code_is_registered():
    missing = {c: where for c, where in _emitted().items() if c not in CODES}
    assert not missing, f"unregistered diagnostic codes: {missing}"


def test_every_registered_code_is_emitted():
    unused = sorted(set(CODES) - set(_emitted()))
    assert not unused, f"registered but never emitted: {unused}"


def test_one_scheme_and_stage_by_number():
    for code, info in CODES.items():
        assert SCHEME.match(code), code
        assert info.meaning
        if code[0] in "EW":
            assert STAGE_OF_HUNDREDS[int(code[1:]) // 100] is info.stage, code
        else:
            assert info.stage is Stage.GR1, code


def test_no_code_is_both_three_and_four_digits():
    # the old collisions: E302/E0302, E501/E0501, E0901/E501
    short = {c for c in _emitted() if re.fullmatch(r"[EW]\d{3}", c)}
    assert not short, short
