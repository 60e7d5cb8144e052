"""Restart back-off for CUDD's dynamic reordering inside one fused relational product.

The problem.  CUDD reorders when the live nodes pass a trigger; after a sift the trigger is
``2 · (live nodes the sift left)`` (after 20 reorderings: the old trigger + 20 when that is
larger; ``Cudd_ReduceHeap``, cuddReorder.c).  A reordering inside a fused operation
(``Cudd_bddAndAbstract``, our :func:`~iterplan_compiler.symbolic.bdd.and_exists`) aborts it:
its partial results die, the sift sees only the operands, and the operation restarts from
scratch.  When the product needs more than twice its operands' nodes under the order that
sift leaves, it crosses the same trigger again, sifts to the same small heap, restarts ...
The published synt15 n=60 spent 103 of its 104 s in one ``and_exists`` doing 1624 sifts of
~60 ms each (docs/gr1.md, "Published instances").

The rule (:func:`raised_trigger`).  CUDD's rule stands for the first :data:`KEPT`
reorderings inside one fused product: a product that grows gets its doubling from CUDD
itself (our synt15 encoding sifts 6 times inside one product and is better for it).  From
then on every further reordering inside the same product at least doubles the previous
trigger (exponential back-off, as for any retried operation), so a product of peak size P
restarts at most ``KEPT + log2(P / trigger)`` times and its recomputation is a geometric
sum.  Reorderings outside fused products are never touched.
The BDDs computed are the same either way; only when CUDD sifts changes.

How.  ``dd.cudd`` 0.6.0 wraps neither CUDD's reordering hooks nor
``Cudd_SetNextReordering``, but its extension module exports both, so they are called with
``ctypes`` on the manager's ``DdManager *``, read from the Cython object (the field after the
object header and the vtable pointer).  That read is made only for a dd version whose layout
was checked (:data:`KNOWN_DD`) and is used only after the pointer reproduces four settings the
manager reports through dd's own API; otherwise :func:`install` returns None and CUDD's rule
applies unchanged.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass, field
from typing import Any

#: dd versions whose ``dd.cudd.BDD`` layout (manager pointer at byte 24) was checked.
KNOWN_DD = ("0.6.0",)
#: Reorderings inside one fused product left at CUDD's own trigger (see the module text).
#: Measured (docs/gr1.md, "Restart back-off"): 1 raised the trigger in amba_jcss12 n=5 and
#: slowed it ~15 %; 4 leaves the regression set's instances at CUDD's rule, except the
#: thrashing product and two of our synt15 n=60's.
KEPT = 4

_POST_REORDERING_HOOK = 3  # Cudd_HookType: PRE_GC, POST_GC, PRE_REORDERING, POST_REORDERING
_HOOK = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_void_p)
_SIGNATURES: dict[str, tuple[list[Any], Any]] = {
    "Cudd_ReadNextReordering": ([ctypes.c_void_p], ctypes.c_uint),
    "Cudd_SetNextReordering": ([ctypes.c_void_p, ctypes.c_uint], None),
    "Cudd_ReadMaxGrowth": ([ctypes.c_void_p], ctypes.c_double),
    "Cudd_ReadMinHit": ([ctypes.c_void_p], ctypes.c_uint),
    "Cudd_ReadSiftMaxSwap": ([ctypes.c_void_p], ctypes.c_int),
    "Cudd_ReadSiftMaxVar": ([ctypes.c_void_p], ctypes.c_int),
    "Cudd_AddHook": ([ctypes.c_void_p, _HOOK, ctypes.c_int], ctypes.c_int),
}
# CUDD keeps calling a hook for as long as its manager lives, and a manager may outlive the
# objects that installed it: the callbacks are never released (one small closure per game).
_keep_alive: list[Any] = []
_lib: Any = None


def raised_trigger(repeats: int, last_trigger: int, own: int) -> int | None:
    """The trigger to set after the ``repeats``-th consecutive reordering inside one fused
    product (1 = the first), given the trigger after the previous one and CUDD's own new
    trigger ``own``; None: keep CUDD's."""
    if repeats <= KEPT:
        return None
    floor = 2 * last_trigger
    return floor if own < floor else None


@dataclass
class Backoff:
    """The back-off attached to one manager: :meth:`enter` / :meth:`leave` bracket each
    fused product (mutable run-time state, updated by CUDD's post-reordering hook)."""

    depth: int = 0         # > 0 while a fused product runs
    epoch: int = 0         # fused products started so far
    last_epoch: int = -1   # the product of the last reordering (-1: none / outside)
    repeats: int = 0       # consecutive reorderings inside that product
    last_trigger: int = 0  # the trigger after the last reordering, as finally set
    seen: int = 0          # reorderings the hook saw
    raised: int = 0        # ... of which had their trigger raised
    _hook: Any = field(default=None, repr=False)

    def enter(self) -> None:
        self.depth += 1
        self.epoch += 1

    def leave(self) -> None:
        self.depth -= 1

    def after_reordering(self, own: int) -> int | None:
        """Account one reordering (CUDD's new trigger ``own``); the trigger to set instead."""
        self.seen += 1
        inside = self.depth > 0
        same = inside and self.epoch == self.last_epoch
        self.repeats = self.repeats + 1 if same else (1 if inside else 0)
        new = raised_trigger(self.repeats, self.last_trigger, own) if same else None
        if new is not None:
            self.raised += 1
        self.last_epoch = self.epoch if inside else -1
        self.last_trigger = own if new is None else new
        return new


def _cudd_lib() -> Any:
    global _lib
    if _lib is None:
        import dd.cudd

        lib = ctypes.CDLL(dd.cudd.__file__)
        for name, (args, res) in _SIGNATURES.items():
            fn = getattr(lib, name)
            fn.argtypes, fn.restype = args, res
        _lib = lib
    return _lib


def manager_pointer(bdd: Any) -> int | None:
    """``bdd``'s ``DdManager *``, or None unless ``bdd`` is a ``dd.cudd.BDD`` of a
    :data:`KNOWN_DD` version and the pointer reproduces the manager's own settings."""
    try:
        import dd
        import dd.cudd
    except ImportError:
        return None
    if getattr(dd, "__version__", None) not in KNOWN_DD or type(bdd) is not dd.cudd.BDD:
        return None
    lib = _cudd_lib()
    p = ctypes.c_void_p.from_address(id(bdd) + 24).value
    if not p or p % 8:
        return None
    cfg = bdd.configure()
    same = (lib.Cudd_ReadMaxGrowth(p) == cfg["max_growth"]
            and lib.Cudd_ReadMinHit(p) == cfg["min_hit"]
            and lib.Cudd_ReadSiftMaxSwap(p) == cfg["max_swaps"]
            and lib.Cudd_ReadSiftMaxVar(p) == cfg["max_vars"])
    return int(p) if same else None


def next_trigger(bdd: Any) -> int | None:
    """CUDD's current reordering trigger of ``bdd`` (live nodes), None if unreadable."""
    p = manager_pointer(bdd)
    return None if p is None else int(_cudd_lib().Cudd_ReadNextReordering(p))


def install(bdd: Any) -> Backoff | None:
    """Attach a :class:`Backoff` to the ``dd.cudd.BDD`` ``bdd`` (once per manager); None if
    it cannot be (not CUDD, another dd version, pointer check failed): nothing changed."""
    p = manager_pointer(bdd)
    if p is None:
        return None
    lib = _cudd_lib()
    state = Backoff()

    def post(mgr: int, _what: bytes, _data: int) -> int:
        # 0 would make CUDD report the reordering as failed: never let an error escape here
        try:
            new = state.after_reordering(int(lib.Cudd_ReadNextReordering(mgr)))
            if new is not None:
                lib.Cudd_SetNextReordering(mgr, new)
        except Exception:  # pragma: no cover - defensive: CUDD's own trigger stays
            pass
        return 1

    hook = _HOOK(post)
    if not lib.Cudd_AddHook(p, hook, _POST_REORDERING_HOOK):
        return None
    _keep_alive.append(hook)
    state._hook = hook
    return state
