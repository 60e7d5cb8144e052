"""What each experiment of Fig. 3 varies, and the synthetic maps its cases fly over.

A :class:`Case` is one simulated mission: an experiment name, the number of locations in the
iterator (the *universe*), the number of locations to cover (Cover only), a sorter and a seed.
Full sizes follow the paper (Ordered Patrol up to 700,000 locations; Cover with a 713-location
universe; Cover of 61 locations for growing universes), 30 runs per point (the paper: 6 for
Cover); what a seed varies is :func:`layout`;
``quick`` sizes are small enough for CI.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

from iterplan_compiler.runtime.sorter import SorterKind, sorter_kind


class Experiment(enum.Enum):
    """What ``iterc experiment NAME`` runs: the trajectories of Fig. 3(a), the sweeps of
    Fig. 3(b)-(d) (:data:`EXPERIMENTS`, the experiment of a :class:`Case`), the synthesis-time
    table, or ``all`` of them in this order (:meth:`expand`)."""

    FIG3A = "fig3a"
    FIG3B = "fig3b"
    FIG3C = "fig3c"
    FIG3D = "fig3d"
    SYNTHESIS_TABLE = "synthesis-table"
    ALL = "all"

    def expand(self) -> tuple[Experiment, ...]:
        """The experiments this choice runs (``ALL``: every other member, in order)."""
        if self is Experiment.ALL:
            return tuple(e for e in Experiment if e is not Experiment.ALL)
        return (self,)


SORTERS: tuple[str, ...] = tuple(k.value for k in SorterKind)
#: the sweeps (their cases are flown by :class:`missions.Runner`)
EXPERIMENTS: tuple[Experiment, ...] = (Experiment.FIG3B, Experiment.FIG3C, Experiment.FIG3D)

#: Patrol locations of Fig. 3(b) as (col, row) cells, near the launch cell (0, 0), visited in
#: this order.  The universe grows around them (the paper's Fig. 3(a)).
PATROL_CELLS: tuple[tuple[int, int], ...] = ((2, 2), (9, 3), (5, 9))
#: South-west corner (col, row) of the Cover region.
COVER_OFFSET: tuple[int, int] = (4, 4)
COVER_UNIVERSE_3C = 713
COVER_COUNT_3D = 61


@dataclass(frozen=True)
class Case:
    """One simulated mission.  ``count`` is the number of locations to cover (Cover) or of
    patrol locations (Ordered Patrol); ``loops`` the number of patrol loops measured.
    ``experiment`` and ``sorter`` may be given by their values (``"fig3b"``, ``"last"``):
    they are converted to the enums here."""

    experiment: Experiment
    universe: int
    count: int
    sorter: SorterKind
    seed: int
    loops: int = 1

    def __post_init__(self) -> None:
        object.__setattr__(self, "experiment", Experiment(self.experiment))
        object.__setattr__(self, "sorter", sorter_kind(self.sorter))

    def values(self) -> tuple[str, int, int, str, int, int]:
        """The fields as written to the CSV (the enums by their values), in field order."""
        return (self.experiment.value, self.universe, self.count, self.sorter.value,
                self.seed, self.loops)


@dataclass(frozen=True)
class SweepConfig:
    """Sizes of one experiment."""

    experiment: Experiment
    universes: tuple[int, ...]
    counts: tuple[int, ...]
    seeds: int
    sorters: tuple[SorterKind, ...] = tuple(SorterKind)
    loops: int = 1


FULL: dict[Experiment, SweepConfig] = {
    Experiment.FIG3B: SweepConfig(Experiment.FIG3B,
                                  (1_000, 10_000, 50_000, 100_000, 200_000, 400_000, 700_000),
                                  (3,), seeds=30, loops=2),
    Experiment.FIG3C: SweepConfig(Experiment.FIG3C, (COVER_UNIVERSE_3C,),
                                  (10, 25, 61, 100, 150, 200, 300), seeds=30),
    Experiment.FIG3D: SweepConfig(Experiment.FIG3D,
                                  (200, 713, 2_000, 10_000, 50_000, 100_000, 200_000),
                                  (COVER_COUNT_3D,), seeds=30),
}

QUICK: dict[Experiment, SweepConfig] = {
    Experiment.FIG3B: SweepConfig(Experiment.FIG3B, (144, 400), (3,), seeds=2, loops=1),
    Experiment.FIG3C: SweepConfig(Experiment.FIG3C, (COVER_UNIVERSE_3C,), (6, 16), seeds=2),
    Experiment.FIG3D: SweepConfig(Experiment.FIG3D, (169, 400), (16,), seeds=2),
}


def sweep(experiment: Experiment, *, quick: bool = False, seeds: int | None = None,
          sorters: tuple[SorterKind, ...] | None = None,
          universes: tuple[int, ...] | None = None,
          counts: tuple[int, ...] | None = None) -> list[Case]:
    """The cases of one experiment, in a deterministic order (largest first, so the slow
    cases start early when run in parallel).  ``universes`` / ``counts`` override the
    configured sizes."""
    table = QUICK if quick else FULL
    if experiment not in table:
        raise ValueError(f"unknown experiment {getattr(experiment, 'value', experiment)!r}; "
                         f"expected one of {', '.join(e.value for e in EXPERIMENTS)}")
    cfg = table[experiment]
    n_seeds = cfg.seeds if seeds is None else seeds
    if n_seeds < 1:
        raise ValueError("seeds must be at least 1")
    cases = [Case(experiment, u, c, s, seed, cfg.loops)
             for u in (universes or cfg.universes) for c in (counts or cfg.counts)
             for s in (sorters or cfg.sorters) for seed in range(n_seeds)]
    for case in cases:
        check_case(case)
    return sorted(cases, key=lambda c: (-c.universe * max(c.count, 1), c.values()))


def grid_shape(universe: int) -> tuple[int, int]:
    """(cols, rows) of the near-square grid holding ``universe`` locations (the last row may be
    partial)."""
    if universe < 1:
        raise ValueError("universe must be positive")
    cols = math.ceil(math.sqrt(universe))
    rows = math.ceil(universe / cols)
    return cols, rows


def region_cells(count: int, offset: tuple[int, int] = COVER_OFFSET) -> list[tuple[int, int]]:
    """``count`` contiguous (col, row) cells: row by row in a near-square block at ``offset``."""
    side = math.ceil(math.sqrt(count))
    return [(offset[0] + i % side, offset[1] + i // side) for i in range(count)]


#: The launch cell of every seed lies in this many columns/rows at the SW corner.
HOME_BOX = 3
#: Cover regions are placed with their SW corner this many cells from the home box at most.
REGION_SPREAD = 8


@dataclass(frozen=True)
class Layout:
    """What a seed varies (as the paper's runs do): the region's SW corner (Cover), the launch
    cell and the launch heading (math radians); the random sorter's order varies with the seed
    too (``RunConfig.seed``)."""

    offset: tuple[int, int]
    home: tuple[int, int]
    heading: float


def layout(case: Case) -> Layout:
    """The seed's layout: deterministic in (experiment, universe, count, seed), the same for
    every sorter so that sorters are compared on the same missions."""
    import numpy as np

    exp_id = EXPERIMENTS.index(case.experiment) if case.experiment in EXPERIMENTS else 9
    rng = np.random.default_rng([case.seed, case.universe, case.count, exp_id])
    cols, rows = grid_shape(case.universe)
    full_rows = case.universe // cols            # rows with every column a location
    home = (int(rng.integers(0, min(HOME_BOX, cols))), int(rng.integers(0, min(HOME_BOX,
                                                                               full_rows))))
    heading = float(rng.uniform(0.0, 2 * math.pi))
    offset = COVER_OFFSET
    if case.experiment is not Experiment.FIG3B:
        side = math.ceil(math.sqrt(case.count))
        height = math.ceil(case.count / side)
        lo = HOME_BOX + 1
        hi_c = min(cols - side, lo + REGION_SPREAD)
        hi_r = min(full_rows - height, lo + REGION_SPREAD)
        if hi_c >= lo and hi_r >= lo:
            offset = (int(rng.integers(lo, hi_c + 1)), int(rng.integers(lo, hi_r + 1)))
        else:
            offset = (max(0, min(lo, cols - side)), max(0, min(lo, full_rows - height)))
    return Layout(offset, home, heading)


def cell_name(col: int, row: int) -> str:
    """The map schema's cell name (``A1`` = column 0, row 0)."""
    letters, c = "", col + 1
    while c:
        c, rem = divmod(c - 1, 26)
        letters = chr(65 + rem) + letters
    return f"{letters}{row + 1}"


def check_case(case: Case) -> None:
    """Raise ValueError if the case's special cells do not fit in its universe."""
    cols, rows = grid_shape(case.universe)
    if case.experiment is Experiment.FIG3B:
        special = list(PATROL_CELLS[: case.count])
        if case.count > len(PATROL_CELLS):
            raise ValueError(f"at most {len(PATROL_CELLS)} patrol locations are placed")
    else:
        special = region_cells(case.count, layout(case).offset)
    for col, row in special:
        if col >= cols or row * cols + col >= case.universe:
            raise ValueError(f"{case}: cell ({col}, {row}) is outside a {case.universe}-location "
                             f"universe ({cols} columns)")


def case_map_data(case: Case) -> dict:
    """The case's map in the runtime's map schema (``runtime.grid.load_map(data=...)``), plus
    ``"cells"``: the number of leading cell ids (row-major) that are locations."""
    cols, rows = grid_shape(case.universe)
    lay = layout(case)
    data: dict = {
        "name": f"{case.experiment.value}-{case.universe}-{case.count}",
        "cell_size": 50,
        "cols": cols,
        "rows": rows,
        "home": {"cell": cell_name(*lay.home)},
        "arrival_heading": 0,
        "sensors": {},
    }
    if case.experiment is Experiment.FIG3B:
        for i, (c, r) in enumerate(PATROL_CELLS[: case.count]):
            data["sensors"][f"p.{i}"] = [[c, r]]
    else:
        data["sensors"]["cover"] = [[c, r] for c, r in region_cells(case.count, lay.offset)]
    return data
