"""Print an explicit LTS as an FSP process definition, in the style of MTSA's FSP export.

Example output (tabs shown as spaces)::

    EXPECTED = Q0,
        Q0  = (a -> Q1
              |{b, c} -> ERROR),
        Q1  = (_tau -> Q2),
        Q2  = END+{d}\\{_tau}.

Contract of :func:`lts_to_fsp`:

* state ``i`` is the local process ``Qi``; the definition starts ``NAME = Q<initial>``;
* moves from one state to one target are grouped into a label set ``{a, b} -> Qj`` (labels
  sorted), groups ordered by their first label then target; ERROR targets print ``ERROR``;
* a state without moves prints ``END`` if it is an END state, else ``STOP``;
* ``tau`` prints as ``_tau`` and the definition ends with ``\\{_tau}`` (MTSA's convention), so
  parsing the text back gives tau moves again;
* only states reachable from the initial state are printed (numbers kept, so there may be
  gaps); alphabet labels that label no reachable move are added with ``+{...}``, so the
  alphabet round-trips whether or not a reader counts labels of unreachable locals;
* label components that are integers print as indices (``s.4`` → ``s[4]``), as MTSA does;
* a name that is not an FSP process identifier is sanitised (``C_#NC#`` → ``C__NC_``), and a
  name of the form ``Q<n>`` gets a trailing ``_`` so it cannot clash with a local.

The output is deterministic and ends with a newline.
"""

from __future__ import annotations

import re

from .lts import ERROR, LTS, TAU

__all__ = ["format_label", "lts_to_fsp", "process_name"]

_TAU_PRINTED = "_tau"
_UID = re.compile(r"[A-Z][A-Za-z0-9_]*\Z")
_STATE = re.compile(r"Q[0-9]+\Z")


def process_name(name: str) -> str:
    """Turn an arbitrary LTS name into an FSP process identifier (uppercase first letter)."""
    if _UID.match(name) and not _STATE.match(name):
        return name
    if _STATE.match(name):  # would clash with the local names Q0, Q1, ...
        return name + "_"
    cleaned = re.sub(r"[^A-Za-z0-9_]", "_", name)
    if not cleaned or not cleaned[0].isalpha():
        cleaned = "P" + cleaned
    return cleaned[0].upper() + cleaned[1:]


def format_label(label: str) -> str:
    """Print a dotted label with integer components as indices: ``a.1.b`` → ``a[1].b``."""
    if label == TAU:
        return _TAU_PRINTED
    parts = label.split(".")
    out = [parts[0]]
    for part in parts[1:]:
        if re.fullmatch(r"-?[0-9]+", part):
            out.append(f"[{part}]")
        else:
            out.append("." + part)
    return "".join(out)


def _reachable_states(initial: int, groups: list[dict[int, list[str]]]) -> list[int]:
    seen = {initial}
    stack = [initial]
    while stack:
        s = stack.pop()
        for t in groups[s]:
            if t != ERROR and t not in seen:
                seen.add(t)
                stack.append(t)
    return sorted(seen)


def lts_to_fsp(lts: LTS) -> str:
    """Return ``lts`` as one FSP process definition (see the module doc for the format)."""
    groups: list[dict[int, list[str]]] = [{} for _ in range(lts.num_states)]
    for s, a, t in lts.transitions:
        groups[s].setdefault(t, []).append(a)

    def target(t: int) -> str:
        return "ERROR" if t == ERROR else f"Q{t}"

    live = _reachable_states(lts.initial, groups)
    used_live = {a for s in live for labels in groups[s].values() for a in labels}
    if TAU in used_live and not (lts.alphabet - used_live) and not groups[live[-1]]:
        # `Qn = STOP\{_tau}.` would read as the label difference `STOP \ {_tau}`: end the
        # definition with a state that has moves (order of locals is free in FSP).
        moving = [s for s in live if groups[s]]
        live.remove(moving[-1])
        live.append(moving[-1])
    lines = [f"{process_name(lts.name)} = Q{lts.initial},"]
    used: set[str] = set()
    for s in live:
        entries = sorted(
            (sorted(format_label(a) for a in labels), t) for t, labels in groups[s].items()
        )
        for labels in groups[s].values():
            used.update(labels)
        if not entries:
            body = "END" if s in lts.end_states else "STOP"
        else:
            choices = []
            for labels, t in entries:
                lab = labels[0] if len(labels) == 1 else "{" + ", ".join(labels) + "}"
                choices.append(f"{lab} -> {target(t)}")
            body = "(" + "\n\t\t  |".join(choices) + ")"
        sep = "," if s != live[-1] else ""
        lines.append(f"\tQ{s}\t= {body}{sep}")
    tail = ""
    unused = sorted(lts.alphabet - used)
    if unused:
        tail += "+{" + ", ".join(format_label(a) for a in unused) + "}"
    if TAU in used:
        tail += "\\{" + _TAU_PRINTED + "}"
    return "\n".join(lines) + tail + ".\n"
