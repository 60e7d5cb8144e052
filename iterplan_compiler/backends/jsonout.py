"""JSON back-end: an LTS (typically a synthesised controller) as stable, diff-friendly JSON.

Schema (``"format": "iterplan-lts/1"``)::

    {"format": "iterplan-lts/1", "name": str, "num_states": int, "initial": int,
     "alphabet": [sorted labels], "controllable": [sorted], "uncontrollable": [sorted],
     "end_states": [sorted], "state_names": [str] | null,
     "transitions": [[source, label, target], ...]}   # target -1 = ERROR; sorted

``controllable`` is intersected with the alphabet; ``uncontrollable`` is the rest of the
alphabet.  Keys are sorted and the text ends with a newline, so equal machines give equal bytes.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from typing import Any

from iterplan_compiler.ir.lts import LTS, make_lts

FORMAT = "iterplan-lts/1"


def to_dict(lts: LTS, controllable: Iterable[str] = ()) -> dict[str, Any]:
    """Return the JSON-ready dictionary described in the module docstring."""
    ctrl = frozenset(controllable) & lts.alphabet
    return {
        "format": FORMAT,
        "name": lts.name,
        "num_states": lts.num_states,
        "initial": lts.initial,
        "alphabet": sorted(lts.alphabet),
        "controllable": sorted(ctrl),
        "uncontrollable": sorted(lts.alphabet - ctrl),
        "end_states": sorted(lts.end_states),
        "state_names": list(lts.state_names) if lts.state_names is not None else None,
        "transitions": [[s, a, t] for s, a, t in lts.transitions],
    }


def to_json(lts: LTS, controllable: Iterable[str] = ()) -> str:
    """Return ``lts`` as JSON text (one transition per line; byte-stable)."""
    d = to_dict(lts, controllable)
    trans = d.pop("transitions")
    head = json.dumps(d, sort_keys=True, indent=1, ensure_ascii=False)
    # One transition per line keeps big controllers diffable without json's one-token lines.
    rows = ",\n".join("  " + json.dumps(t, ensure_ascii=False) for t in trans)
    assert head.endswith("\n}")  # json.dumps(indent=1) of a non-empty dict
    listing = f"[\n{rows}\n ]" if rows else "[]"
    return head[:-2] + f',\n "transitions": {listing}\n}}\n'


def from_json(text: str) -> tuple[LTS, frozenset[str]]:
    """Parse :func:`to_json` output back into ``(lts, controllable)`` (round-trip helper)."""
    d = json.loads(text)
    if d.get("format") != FORMAT:
        raise ValueError(f"not an {FORMAT} document")
    lts = make_lts(
        d["name"], d["num_states"], (tuple(t) for t in d["transitions"]), d["alphabet"],
        d["initial"], d["end_states"], d["state_names"],
    )
    return lts, frozenset(d["controllable"])
