"""An on-disk cache of parsed spec files (the :class:`~.syntax.SpecFile` and its diagnostics).

Parsing is a pure function of

    (the text, its path (spans name it), ``allow_mts``, the limits in force,
     the grammar, the Lark release, the source of the parsing modules)

but in a fresh process it is the most expensive step of ``iterc compile`` on the paper's
tasks: importing Lark, loading its parse table and compiling the regular expressions of the
contextual lexer's ~60 per-state scanners cost ~0.2 s before the first token, for files of a
few hundred lines (four of them per task: the spec and its three ``include``\\ d stdlib
files).  So the result is kept between runs, keyed by a SHA-256 of all those inputs; a
changed parser, grammar or Lark never reads an old entry, and a hit does not import Lark.

Only parses without errors are stored (an input with errors is about to be edited; it also
keeps fuzzed inputs from filling the folder).  Entries are pickles (restoring thousands of
frozen syntax nodes from JSON in Python would cost about as much as parsing), written
atomically in the user's cache folder (:func:`iterplan_compiler.outputs.user_cache_dir`),
like Lark's own parse-table cache next to it; ``ITERPLAN_NO_CACHE=1`` disables the cache, and
an unreadable or mismatching entry is a miss.
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib.resources
import importlib.util
import pickle
import sys
from functools import lru_cache
from pathlib import Path

from iterplan_compiler import limits
from iterplan_compiler.diagnostics import Diagnostic
from iterplan_compiler.frontend import syntax as S
from iterplan_compiler.outputs import atomic_write_bytes, user_cache_dir

#: bumped when the entry layout changes
_FORMAT = 1

#: the modules whose code decides a parse's result (``syntax`` re-exports ``syntax_nodes``)
_PARSER_MODULES = ("parse.py", "tree_to_ast.py", "errors.py", "syntax.py", "syntax_nodes.py",
                   "syntax_cache.py")


@lru_cache(maxsize=1)
def _parser_hash() -> str:
    """A hash of everything but the input that decides the result: the parsing modules, the
    diagnostics and limits they use, the grammar, Lark's release (its ``__init__.py`` carries
    the version; read, not imported) and Python's version (pickle, ``Fraction``)."""
    here = Path(__file__).parent
    h = hashlib.sha256(f"{_FORMAT} {sys.version}".encode())
    for name in _PARSER_MODULES:
        h.update((here / name).read_bytes())
    for name in ("diagnostics.py", "limits.py"):
        h.update((here.parent / name).read_bytes())
    h.update(importlib.resources.files("iterplan_compiler.grammar").joinpath("fsp.lark")
             .read_bytes())
    spec = importlib.util.find_spec("lark")
    h.update(Path(spec.origin).read_bytes() if spec is not None and spec.origin else b"-")
    return h.hexdigest()


def cache_key(text: str, path: str, allow_mts: bool) -> str:
    """The entry's key for parsing ``text`` as ``path`` under the current limits."""
    h = hashlib.sha256(_parser_hash().encode())
    h.update(repr((path, allow_mts, dataclasses.astuple(limits.current()))).encode())
    h.update(b"\0")
    h.update(text.encode("utf-8", "surrogatepass"))
    return h.hexdigest()


def _entry(key: str) -> Path | None:
    folder = user_cache_dir("syntax")
    return None if folder is None else folder / f"{key[:32]}.pickle"


def load(key: str) -> tuple[S.SpecFile, list[Diagnostic]] | None:
    """The cached parse stored under ``key``, or None."""
    path = _entry(key)
    if path is None:
        return None
    try:
        stored_key, spec, diags = pickle.loads(path.read_bytes())
    except Exception:  # noqa: BLE001 - a missing, truncated or stale entry is a miss
        return None
    if stored_key != key or not isinstance(spec, S.SpecFile) or not isinstance(diags, list):
        return None
    return spec, diags


def store(key: str, spec: S.SpecFile, diags: list[Diagnostic]) -> None:
    """Keep a parse without errors under ``key``."""
    if any(d.is_error for d in diags):
        return
    path = _entry(key)
    if path is None:
        return
    try:
        data = pickle.dumps((key, spec, diags), protocol=pickle.HIGHEST_PROTOCOL)
        atomic_write_bytes(path, data)
    except (OSError, RecursionError, pickle.PicklingError):
        pass  # a cache that cannot be written (or a tree too deep to pickle) is skipped


def parse_text(text: str, path: str = "<input>", *, allow_mts: bool = False
               ) -> tuple[S.SpecFile, list[Diagnostic]]:
    """:func:`.parse.parse_text`, through the cache: Lark is imported only on a miss."""
    key = cache_key(text, path, allow_mts)
    hit = load(key)
    if hit is not None:
        return hit
    from iterplan_compiler.frontend import parse  # Lark and its tables: only when parsing

    spec, diags = parse.parse_text(text, path, allow_mts=allow_mts)
    store(key, spec, diags)
    return spec, diags
