"""Sequential process definitions → explicit LTSs (``mtsa-semantics.md`` §2.2–2.4).

:func:`build_process` instantiates one :class:`~syntax.ProcessDecl` with actual parameter
values.  States are created lazily from the initial state, so only reachable local instances
are built; intermediate states of prefix chains are cached per (syntax node, bound variables)
so ``{a,b} -> c -> P`` shares one intermediate state.  A reference to an undefined local
becomes a transition to ERROR with warning W0301 (MTSA's idiom).

Codes: W0301 local defined to be ERROR, E0302 local state defined twice, E0303 alias cycle,
E0305 `;` item is not sequential.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from iterplan_compiler import limits
from iterplan_compiler.diagnostics import Diagnostic, Related, Span, error, warning
from iterplan_compiler.frontend import syntax as S
from iterplan_compiler.frontend.expressions import (
    Env,
    EvalError,
    Value,
    bind_all,
    evaluate,
    expand_label_env,
    fmt,
    part_values,
    report,
    truth,
)
from iterplan_compiler.ir.lts import ERROR, LTS, TAU, make_lts

# callback: (name, args, span) -> LTS of another process instance (for P(2) and A;B)
ProcessGetter = Callable[[str, tuple[Value, ...], Span], "LTS | None"]


@dataclass
class _Builder:
    decl: S.ProcessDecl
    env: Env
    name: str
    get_process: ProcessGetter
    diags: list[Diagnostic]
    locals: dict[str, tuple[S.StateExpr, Env, Span]] = field(default_factory=dict)
    state_of: dict[str, int] = field(default_factory=dict)
    in_progress: set[str] = field(default_factory=set)
    cache: dict[tuple, int] = field(default_factory=dict)
    trans: list[tuple[int, str, int]] = field(default_factory=list)
    alphabet: set[str] = field(default_factory=set)
    n: int = 0
    stop: int | None = None
    end: int | None = None
    warned: set[str] = field(default_factory=set)

    def new_state(self) -> int:
        self.n += 1
        return self.n - 1

    # -- locals
    def collect_locals(self) -> None:
        self.locals[self.decl.name] = (self.decl.body, self.env, self.decl.span)
        for ld in self.decl.locals:
            for key, env in self.local_keys(ld):
                if key in self.locals:
                    prev = self.locals[key][2]
                    self.diags.append(error(
                        "E0302", f"local process '{key}' is defined twice in {self.decl.name}",
                        ld.span, Related(prev, "first definition here")))
                    continue
                self.locals[key] = (ld.body, env, ld.span)

    def local_keys(self, ld: S.LocalDef) -> list[tuple[str, Env]]:
        acc: list[tuple[str, Env]] = [(ld.name, self.env)]
        for part in ld.indices:
            nxt = []
            for key, env in acc:
                for text, e2 in part_values(part, env):
                    nxt.append((f"{key}.{text}", e2))
            acc = nxt
        return acc

    # -- states
    def ref_key(self, ref: S.StateRef, env: Env) -> str:
        key = ref.name
        for ix in ref.indices:
            key += "." + fmt(evaluate(ix, env))
        return key

    def local_state(self, key: str, span: Span) -> int:
        if key in self.state_of:
            return self.state_of[key]
        if key == "STOP":
            if self.stop is None:
                self.stop = self.new_state()
            return self.stop
        if key == "END":
            if self.end is None:
                self.end = self.new_state()
            return self.end
        if key == "ERROR":
            return ERROR
        if key not in self.locals:
            if key not in self.warned:
                self.warned.add(key)
                self.diags.append(warning("W0301", f"{key} defined to be ERROR", span))
            return ERROR
        # Follow aliases (`P = Q`, `P = if c then Q else R`) syntactically to the defining
        # choice expression, so that mutually recursive locals through an alias work.
        seen = [key]
        body, env, _ = self.locals[key]
        while True:
            if isinstance(body, S.IfState):
                if truth(evaluate(body.cond, env), body.span):
                    body = body.then
                else:
                    body = body.other if body.other is not None else S.StateRef("STOP")
                continue
            if isinstance(body, S.StateRef) and body.args is None:
                k2 = self.ref_key(body, env)
                if k2 in self.state_of:
                    s = self.state_of[k2]
                    break
                if k2 in ("STOP", "END", "ERROR") or k2 not in self.locals:
                    s = self.local_state(k2, body.span)
                    break
                if k2 in seen:
                    self.diags.append(error("E0303", f"local process '{k2}' is defined only "
                                            "in terms of itself", span))
                    s = ERROR
                    break
                seen.append(k2)
                body, env, _ = self.locals[k2]
                continue
            if isinstance(body, S.Choices):
                s = self.new_state()
                for k in seen:
                    self.state_of[k] = s
                self.fill_choices(s, body, env)
                return s
            if isinstance(body, (S.SeqComp, S.StateRef)):
                # `P = A; B; P` refers back to P: allocate P's state first and make it the
                # start of the spliced copy of A.
                s = self.new_state()
                for k in seen:
                    self.state_of[k] = s
                if isinstance(body, S.SeqComp):
                    self.splice(list(body.items[:-1]), env, body.items[-1], start=s)
                else:
                    self.splice([body], env, None, start=s)
                return s
            if key in self.in_progress:
                self.diags.append(error("E0303", f"local process '{key}' is defined only in "
                                        "terms of itself", span))
                return ERROR
            self.in_progress.add(key)
            try:
                s = self.state(body, env)
            finally:
                self.in_progress.discard(key)
            break
        for k in seen:
            self.state_of[k] = s
        return s

    def state(self, st: S.StateExpr, env: Env) -> int:
        if isinstance(st, S.StateRef):
            if st.args is not None:
                return self.splice([st], env, None)
            return self.local_state(self.ref_key(st, env), st.span)
        if isinstance(st, S.IfState):
            if truth(evaluate(st.cond, env), st.span):
                return self.state(st.then, env)
            if st.other is None:
                return self.local_state("STOP", st.span)
            return self.state(st.other, env)
        if isinstance(st, S.SeqComp):
            return self.splice(list(st.items[:-1]), env, st.items[-1])
        key = (id(st), env.key())
        if key in self.cache:
            return self.cache[key]
        s = self.new_state()
        self.cache[key] = s
        self.fill_choices(s, st, env)
        return s

    def fill_choices(self, s: int, ch: S.Choices, env: Env) -> None:
        envs = list(bind_all(ch.foreach, env))
        for e0 in envs:
            for c in ch.choices:
                if c.guard is not None and not truth(evaluate(c.guard, e0), c.span):
                    continue
                self.chain(s, c, 0, e0)

    def chain(self, s: int, c: S.Choice, i: int, env: Env) -> None:
        """The prefix chain ``l_i -> ... -> target`` of choice ``c`` from state ``s``.

        A depth-first walk with an explicit stack (a 1000-action sequence must not hit
        Python's recursion limit); it numbers states and emits transitions in the same order
        as the obvious recursive version: a state is created when first reached, the move
        into it is recorded once the chain behind it is done."""
        # a frame: [state, index, label iterator, pending transition or None]
        stack: list[list[Any]] = [[s, i, iter(expand_label_env(c.labels[i], env)), None]]
        while stack:
            frame = stack[-1]
            if frame[3] is not None:
                self.trans.append(frame[3])
                frame[3] = None
            src, k, labels = frame[0], frame[1], frame[2]
            item = next(labels, None)
            if item is None:
                stack.pop()
                continue
            action, e2 = item
            if not len(self.trans) & 0x3FFF:  # every 16,384 transitions: --time-limit
                limits.check_deadline()
            if action == TAU or action.startswith("tau."):
                raise EvalError(error("E0306", "'tau' cannot be used as an action label",
                                      c.labels[k].span))
            self.alphabet.add(action)
            if k + 1 < len(c.labels):
                ck = (id(c), k + 1, e2.key())
                if ck not in self.cache:
                    t = self.new_state()
                    self.cache[ck] = t
                    frame[3] = (src, action, t)
                    stack.append([t, k + 1, iter(expand_label_env(c.labels[k + 1], e2)), None])
                    continue
                self.trans.append((src, action, self.cache[ck]))
            else:
                self.trans.append((src, action, self.state(c.target, e2)))

    def splice(self, items: list[S.StateRef], env: Env, cont: S.StateRef | None,
               start: int | None = None) -> int:
        """``A; B; C``: copy A and B, A's END → B's start, B's END → C (or our END)."""
        if cont is None:
            target = self.local_state("END", items[-1].span) if items else self.local_state(
                "STOP", Span("<seq>", 0, 0))
        else:
            target = self.state(cont, env)
        for ref in reversed(items):
            args = tuple(evaluate(a, env) for a in (ref.args or ()))
            if ref.indices:
                raise EvalError(error("E0305", "indexed process reference in sequential "
                                      "composition", ref.span))
            sub = self.get_process(ref.name, args, ref.span)
            if sub is None:
                return ERROR
            if cont is not None and not sub.end_states:
                raise EvalError(error("E0305", f"'{ref.name}' is not a sequential process "
                                      "(it cannot reach END)", ref.span))
            mapping: dict[int, int] = {}
            first = ref is items[0] and start is not None and sub.initial not in sub.end_states
            for st in range(sub.num_states):
                if st in sub.end_states:
                    mapping[st] = target
                elif first and st == sub.initial:
                    mapping[st] = start  # type: ignore[assignment]
                else:
                    mapping[st] = self.new_state()
            for a, b, t in ((x, y, z) for x, y, z in sub.transitions):
                tt = ERROR if t == ERROR else mapping[t]
                self.trans.append((mapping[a], b, tt))
            self.alphabet |= sub.alphabet
            target = mapping[sub.initial]
        if start is not None and target != start:
            raise EvalError(error("E0305", "sequential composition starting with a process "
                                  "that is already terminated (END) is not supported",
                                  items[0].span))
        return target


def build_process(decl: S.ProcessDecl, env: Env, name: str, get_process: ProcessGetter,
                  diags: list[Diagnostic]) -> LTS | None:
    """Build the raw LTS of one process instance (before tails/keywords).

    Returns ``None`` (with an error appended) when evaluation fails.
    """
    b = _Builder(decl, env, name, get_process, diags)
    try:
        b.collect_locals()
        init = b.local_state(decl.name, decl.span)
    except EvalError as e:
        report(diags, e)
        return None
    trans = b.trans
    n = b.n
    if init == ERROR:
        # `P = ERROR`: one state whose only move is tau to ERROR (§2.2 item 2).
        s0 = n
        n += 1
        trans = [*trans, (s0, TAU, ERROR)]
        init = s0
    if n == 0:
        n = 1
    ends = [b.end] if b.end is not None else []
    return make_lts(name, n, trans, b.alphabet, init, ends)
