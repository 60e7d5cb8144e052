"""The state of an LTS animation (``iterc animate``, ``docs/ltsa.md``): no terminal code here.

An :class:`Animator` walks an explicit LTS one action at a time, like LTSA's animator:

* the *current position* is a set of states (a nondeterministic machine, or one with ``tau``,
  may be in several after the same trace); ``tau`` moves are taken silently (the set is
  tau-closed), so ``tau`` is never offered;
* the *enabled actions* are the labels any current state can fire, sorted; controllable ones
  (``controllable``) are marked;
* fluent values are recomputed from the trace (initiating wins over terminating, as in
  ``fltl/semantics.py``) for the fluents whose actions the machine has;
* :meth:`Animator.undo` steps back; :meth:`Animator.trace_text` is the trace one action a line
  — the format ``iterc animate --script`` reads, so a saved trace replays.

:meth:`Animator.screen` is the text both the interactive and the scripted front-ends print.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from .analysis import tau_closure as _tau_closure
from .formulas import Fluent
from .lts import ERROR, LTS, TAU

__all__ = ["Animator", "AnimationError", "MAX_FLUENTS_SHOWN"]

MAX_FLUENTS_SHOWN = 24


class AnimationError(Exception):
    """A move that the current position does not allow (the message says why)."""


@dataclass
class Animator:
    lts: LTS
    controllable: frozenset[str] = frozenset()
    fluents: Mapping[str, Fluent] = field(default_factory=dict)
    title: str = ""
    #: where ``controllable`` came from (shown on the screen), e.g. "controllerSpec G"
    controllable_origin: str = ""

    def __post_init__(self) -> None:
        self._out: dict[int, list[tuple[str, int]]] = self.lts.out_edges()
        self._start = _tau_closure(self._out, {self.lts.initial})
        self.history: list[tuple[str, frozenset[int]]] = []
        alpha = self.lts.alphabet
        self.shown_fluents = [f for n, f in sorted(self.fluents.items())
                              if (f.initiating | f.terminating) & alpha]

    # ------------------------------------------------------------------ position
    @property
    def states(self) -> frozenset[int]:
        return self.history[-1][1] if self.history else self._start

    @property
    def trace(self) -> list[str]:
        return [a for a, _ in self.history]

    def enabled(self) -> list[str]:
        labels = {a for s in self.states if s != ERROR for a, _ in self._out.get(s, ())}
        labels.discard(TAU)
        return sorted(labels)

    def fire(self, action: str) -> None:
        """Take ``action`` (a name, or a 1-based number in :meth:`enabled`)."""
        enabled = self.enabled()
        if action.isdigit():
            k = int(action)
            if not 1 <= k <= len(enabled):
                raise AnimationError(f"no action number {k}: choose 1..{len(enabled)}"
                                     if enabled else "no action is enabled")
            action = enabled[k - 1]
        if action not in enabled:
            if action in self.lts.alphabet:
                raise AnimationError(f"'{action}' is not enabled here")
            raise AnimationError(f"'{action}' is not an action of {self.lts.name}")
        targets = {t for s in self.states if s != ERROR
                   for a, t in self._out.get(s, ()) if a == action}
        self.history.append((action, _tau_closure(self._out, targets)))

    def undo(self) -> bool:
        """Step back one action; False at the start."""
        if not self.history:
            return False
        self.history.pop()
        return True

    def fluent_values(self) -> dict[str, bool]:
        values = {f.name: f.initially for f in self.shown_fluents}
        for a in self.trace:
            for f in self.shown_fluents:
                if a in f.initiating:
                    values[f.name] = True
                elif a in f.terminating:
                    values[f.name] = False
        return values

    def status(self) -> str:
        """ERROR / END / DEADLOCK notes of the current position ('' if none)."""
        notes = []
        states = self.states
        if ERROR in states:
            notes.append("ERROR reached (a property is violated)")
        if states & self.lts.end_states:
            notes.append("END (successful termination)")
        stuck = sorted(s for s in states if s != ERROR and s not in self.lts.end_states
                       and not self._out.get(s))
        if not self.enabled() and not notes:
            notes.append("DEADLOCK (no action enabled)")
        elif stuck:
            # the trace may also have led to a deadlock state (nondeterminism)
            notes.append(f"possibly DEADLOCK (state {', '.join(map(str, stuck))} has no action)")
        return "; ".join(notes)

    def trace_text(self) -> str:
        return "".join(f"{a}\n" for a in self.trace)

    def save(self, path: str) -> None:
        with open(path, "w", encoding="utf-8") as f:
            f.write(self.trace_text())

    # ------------------------------------------------------------------ screen
    def screen(self) -> str:
        lines = [f"== {self.title or self.lts.name} ({self.lts.num_states} states) =="]
        trace = self.trace
        lines.append(f"trace ({len(trace)}): " + (" ".join(trace) if trace else "(empty)"))
        named = sorted(s for s in self.states if s != ERROR)
        if len(named) == 1 and ERROR not in self.states:
            lines.append(f"state: {named[0]}")
        else:
            shown = [str(s) for s in named] + (["ERROR"] if ERROR in self.states else [])
            lines.append("states: {" + ", ".join(shown) + "}")
        note = self.status()
        if note:
            lines.append(f"status: {note}")
        if self.shown_fluents:
            values = self.fluent_values()
            items = [f"{n}={'true' if v else 'false'}" for n, v in values.items()]
            more = len(items) - MAX_FLUENTS_SHOWN
            items = items[:MAX_FLUENTS_SHOWN] + ([f"(+{more} more)"] if more > 0 else [])
            lines.append("fluents: " + " ".join(items))
        enabled = self.enabled()
        if enabled:
            origin = f", from {self.controllable_origin}" if self.controllable_origin else ""
            mark = f" (* = controllable{origin})" if self.controllable else ""
            lines.append(f"enabled actions{mark}:")
            width = len(str(len(enabled)))
            for k, a in enumerate(enabled, 1):
                star = " *" if a in self.controllable else ""
                lines.append(f"  {k:>{width}}  {a}{star}")
        else:
            lines.append("enabled actions: none")
        return "\n".join(lines)
