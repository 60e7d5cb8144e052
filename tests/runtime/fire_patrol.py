"""Hand-written Fire Patrol controller (the paper's Fig. 2 iterator-based plan) as a module with
the layout ``iterc compile`` emits: a module-level ``TABLE``.

Loop: has.next -> (y.next -> is.next.inP -> (yes.next.inP -> go.next -> arrived -> fire ->
(yes.fire -> take.photo | no.fire) | no.next.inP) -> remove.next) | n.next -> reset.
"""

from iterplan_compiler.runtime.controller import ControllerTable

TRANSITIONS = [
    (0, "has.next", 1),
    (1, "y.next", 2), (1, "n.next", 3),
    (3, "reset", 0),
    (2, "is.next.inP", 4),
    (4, "yes.next.inP", 5), (4, "no.next.inP", 6),
    (6, "remove.next", 0),
    (5, "go.next", 7),
    (7, "arrived", 8),
    (8, "fire", 9),
    (9, "yes.fire", 10), (9, "no.fire", 6),
    (10, "take.photo", 6),
]
CONTROLLABLE = {"has.next", "reset", "is.next.inP", "remove.next", "go.next", "fire",
                "take.photo"}
UNCONTROLLABLE = {"y.next", "n.next", "yes.next.inP", "no.next.inP", "arrived", "yes.fire",
                  "no.fire"}
TABLE = ControllerTable.from_transitions("FirePatrol", 11, TRANSITIONS, CONTROLLABLE,
                                         UNCONTROLLABLE)
