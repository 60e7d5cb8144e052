"""An on-disk cache of compiled safety LTSs (``ltl_property`` / ``constraint``).

Translating a formula into its minimal deterministic safety LTS is the front-end's most
expensive step on the paper's tasks (Ordered Patrol: four formulas, ~43 k progression steps,
about 0.5 s of a 0.9 s ``iterc compile``), and it is a pure function of

    (formula, its ``+ {...}`` alphabet, the fluents, property/constraint, state limit,
     the source of the translation modules)

so its result can be kept between runs.  The key is a SHA-256 of a canonical JSON of those
inputs (sets sorted, spans left out: moving a declaration does not invalidate it; the
translation's own source is hashed in, so a changed translator never reads an old entry).
Only successful translations are stored (errors and warnings are recomputed or derived:
W0604 from the stored "unsatisfiable" bit; see :data:`WORTH_CACHING_S`); the
open-alphabet safety test of :mod:`.open_safety` (E0605) keeps its witness the same way.
Entries are JSON (never pickles), written atomically in the user's cache folder (:func:`iterplan_compiler.outputs.user_cache_dir`);
``ITERPLAN_NO_CACHE=1`` disables the cache, and an unreadable entry is a miss.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path
from typing import Any

from iterplan_compiler.ir.formulas import Fluent, NamedFormula
from iterplan_compiler.ir.lts import LTS, make_lts
from iterplan_compiler.outputs import atomic_write_text, user_cache_dir

#: Translations cheaper than this (CPU seconds) are not stored.  Zero: every successful
#: translation is kept, however cheap.  A warm run whose formulas all hit does not even import
#: the translation's modules (fltl/safety.py), which costs more (~5-15 ms) than the 1-3 ms
#: translations of the paper's tasks; with a 20 ms bound those were translated again on every
#: run (issue #12).  Entries are ~1 KB; the test suite uses a private cache folder.
WORTH_CACHING_S = 0.0

JSONValue = str | int | float | bool | None | list["JSONValue"] | dict[str, "JSONValue"]


def _canonical(value: object) -> JSONValue:
    """A JSON value that is the same for equal inputs in every process (no set order, no
    hash seed, no spans)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {"@": type(value).__name__,
                **{f.name: _canonical(getattr(value, f.name))
                   for f in dataclasses.fields(value) if f.compare}}
    if isinstance(value, (frozenset, set)):
        items = [_canonical(v) for v in value]
        return sorted(items, key=lambda v: json.dumps(v, sort_keys=True))
    if isinstance(value, (tuple, list)):
        return [_canonical(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): _canonical(v) for k, v in sorted(value.items(), key=lambda kv: str(kv[0]))}
    if value is None or isinstance(value, (str, int, float, bool)):
        return value
    return repr(value)


@lru_cache(maxsize=1)
def _translator_hash() -> str:
    """A hash of the modules whose code decides the result."""
    here = Path(__file__).parent
    h = hashlib.sha256()
    for name in ("safety.py", "progression.py", "semantics.py", "emptiness.py",
                 "open_safety.py", "safety_cache.py"):
        h.update((here / name).read_bytes())
    h.update((here.parent / "ir" / "minimise.py").read_bytes())
    return h.hexdigest()


def cache_key(named: NamedFormula, fluents: Mapping[str, Fluent], *, constraint: bool,
              max_states: int) -> str | None:
    """The entry's key; None (not cached) for a formula nested too deeply to walk."""
    try:
        return _key(named, fluents, constraint, max_states)
    except RecursionError:
        return None


def _key(named: NamedFormula, fluents: Mapping[str, Fluent], constraint: bool,
         max_states: int) -> str:
    payload = {"formula": _canonical(named.formula), "extra": _canonical(named.extra_alphabet),
               "fluents": _fluents_json(tuple(sorted(fluents.items()))),
               "constraint": constraint, "max_states": max_states,
               "translator": _translator_hash()}
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()


@lru_cache(maxsize=64)
def _fluents_json(fluents: tuple[tuple[str, Fluent], ...]) -> str:
    """The canonical JSON of a model's fluents, memoised by value (every formula of a model
    has the same fluents in its key; equal fluents have equal canonical forms, since both
    equality and :func:`_canonical` leave spans out)."""
    return json.dumps(_canonical(dict(fluents)), sort_keys=True)


def _entry(key: str, kind: str) -> Path | None:
    folder = user_cache_dir("safety")
    return None if folder is None else folder / f"{kind}-{key[:32]}.json"


def _read(key: str | None, kind: str) -> dict[str, Any] | None:
    path = None if key is None else _entry(key, kind)
    if path is None or key is None:
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) and data.get("key") == key else None


def _write(key: str | None, kind: str, data: dict[str, Any]) -> None:
    path = None if key is None else _entry(key, kind)
    if path is None:
        return
    try:
        atomic_write_text(path, json.dumps({"key": key, **data}, separators=(",", ":")))
    except OSError:
        pass   # a cache that cannot be written is skipped


def load(key: str | None, name: str) -> tuple[LTS, bool] | None:
    """The cached ``(lts, unsatisfiable)`` for ``key`` (renamed ``name``), or None."""
    data = _read(key, "lts")
    if data is None:
        return None
    try:
        names = data.get("state_names")
        lts = make_lts(name, int(data["states"]),
                       [(int(s), str(a), int(t))
                        for s, a, t in data["transitions"]],
                       [str(a) for a in data["alphabet"]],
                       int(data["initial"]),
                       [int(s) for s in data["end_states"]],
                       None if names is None else [str(n) for n in names])
        return lts, bool(data["unsatisfiable"])
    except (ValueError, KeyError, TypeError):
        return None


def store(key: str | None, lts: LTS, unsatisfiable: bool) -> None:
    """Keep ``lts`` under ``key``."""
    _write(key, "lts", {
        "states": lts.num_states, "initial": lts.initial, "alphabet": sorted(lts.alphabet),
        "unsatisfiable": unsatisfiable, "end_states": sorted(lts.end_states),
        "state_names": None if lts.state_names is None else list(lts.state_names),
        "transitions": [list(t) for t in lts.transitions]})


def load_witness(key: str | None) -> tuple[bool, str | None]:
    """``(found, witness)`` of the open-alphabet safety test (fltl/open_safety.py)."""
    data = _read(key, "open")
    if data is None or not isinstance(data.get("witness"), (str, type(None))):
        return False, None
    witness = data["witness"]
    return True, witness if isinstance(witness, str) else None


def store_witness(key: str | None, witness: str | None) -> None:
    _write(key, "open", {"witness": witness})
