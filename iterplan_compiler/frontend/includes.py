"""``include "file.lts"`` (iterplan extension): textual inclusion of reusable fragments.

The path is resolved relative to the including file, then in the bundled ``stdlib/``
(package ``iterplan_compiler.stdlib``).  Included declarations are spliced in at the include
position.  Codes: E0801 file not found or not readable, E0802 include cycle (the message shows the
chain of includes).
"""

from __future__ import annotations

import importlib.resources
from pathlib import Path

from iterplan_compiler.diagnostics import Diagnostic, error
from iterplan_compiler.frontend import syntax as S
from iterplan_compiler.frontend.source import decode, read_spec
from iterplan_compiler.frontend.syntax_cache import parse_text


def _resolve(name: str, including: str) -> tuple[str, str] | str | None:
    """Return (display path, text) of an included file, None if it does not exist, or the
    reason it cannot be read (a name too long for the OS, a NUL byte, permissions...)."""
    base = Path(including).parent if including and not including.startswith("<") else Path(".")
    try:
        cand = base / name
        if cand.is_file():
            text = read_spec(cand)
            return (str(cand), text) if isinstance(text, str) else "not a text file"
        res = importlib.resources.files("iterplan_compiler.stdlib").joinpath(name)
        if res.is_file():
            return f"<stdlib>/{name}", decode(res.read_bytes())
    except (OSError, ValueError) as e:  # ValueError: an embedded NUL byte
        return getattr(e, "strerror", None) or str(e)
    return None


def expand_includes(spec: S.SpecFile, sources: dict[str, str], diags: list[Diagnostic],
                    stack: tuple[str, ...] = ()) -> S.SpecFile:
    """Replace every :class:`~syntax.IncludeDecl` by the declarations of the included file."""
    if not any(isinstance(d, S.IncludeDecl) for d in spec.decls):
        return spec
    out: list[S.Decl] = []
    for d in spec.decls:
        if not isinstance(d, S.IncludeDecl):
            out.append(d)
            continue
        found = _resolve(d.path, spec.path)
        if found is None or isinstance(found, str):
            shown = d.path if len(d.path) <= 80 else d.path[:77] + "..."
            why = ("not found (searched next to the including file and in the bundled stdlib)"
                   if found is None else f"cannot be read: {found}")
            diags.append(error("E0801", f"included file '{shown}' {why}", d.span))
            continue
        path, text = found
        if path in stack or path == spec.path:
            chain = [*stack, spec.path]
            chain = chain[chain.index(path):] if path in chain else chain
            shown_chain = " includes ".join(f"'{p}'" for p in [*chain, path])
            diags.append(error("E0802", f"include cycle: {shown_chain}", d.span))
            continue
        sources[path] = text
        sub, ds = parse_text(text, path)
        diags.extend(ds)
        sub = expand_includes(sub, sources, diags, (*stack, spec.path))
        out.extend(sub.decls)
    return S.SpecFile(spec.path, tuple(out))
