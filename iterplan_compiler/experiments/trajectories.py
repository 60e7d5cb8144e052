"""Fig. 3(a) of the paper: Ordered Patrol trajectories for growing universes (``last`` sorter).

With the ``last`` sorter the next patrol location is offered after every other location, so
the plan iterates over the whole universe before each ``go.next``; with compute-time accounting
the aircraft flies on straight meanwhile, and the loops between the three patrol locations
stretch as the universe grows.
"""

from __future__ import annotations

import io
from pathlib import Path

from iterplan_compiler.experiments.sweeps import PATROL_CELLS, Case, Experiment
from iterplan_compiler.runtime.sorter import SorterKind

FULL_SIZES = (1_000, 100_000, 700_000)
QUICK_SIZES = (144, 1_600, 10_000)


def fly_tracks(ctrl_dir: Path, sizes, sorter: SorterKind = SorterKind.LAST, seed: int = 0,
               loops: int = 1):
    """[(universe, FlightResult, grid)] for one Ordered Patrol mission per size."""
    from iterplan_compiler.experiments import flight, missions

    module = Path(ctrl_dir) / "ordered_patrol_controller.py"
    out = []
    for u in sizes:
        case = Case(Experiment.FIG3B, u, 3, sorter, seed, loops)
        grid = missions.build_grid(case)
        res = flight.fly(module, grid, sorter=sorter, seed=seed,
                         stop=missions.StopWhen(case, grid))
        out.append((u, res, grid))
    return out


def ideal_loop(grid, speed: float) -> float:
    """The ideal loop time (s) of the patrol cells of ``grid`` (p.0, p.1, ... in order)."""
    from iterplan_compiler.experiments.stats import ideal_patrol_loop

    names = sorted(k for k in grid.sensors if k.startswith("p."))
    return ideal_patrol_loop([grid.centre(int(grid.sensors[k][0])) for k in names], speed)


def plot_tracks(runs, path: Path) -> Path:
    """Overlay the flown tracks (from the first patrol visit on) and the patrol cells."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(4.6, 4.6), dpi=120)
    for u, res, _grid in runs:
        t0 = next((e.t for e in res.log if e.label == "visited.p.0"), 0.0)
        pts = [(x, y) for t, x, y in res.track if t >= t0]
        if pts:
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "-", lw=1.0,
                    label=f"{u:,} locations")
    if runs:
        grid = runs[0][2]
        for i, (c, r) in enumerate(PATROL_CELLS):
            x, y = (c + 0.5) * grid.cell_size, (r + 0.5) * grid.cell_size
            ax.plot(x, y, "ks", ms=7)
            ax.annotate(f"p.{i}", (x, y), textcoords="offset points", xytext=(5, 5),
                        fontsize=8)
    ax.set_aspect("equal")
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_title("Ordered Patrol trajectories, 'last' sorter", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    from iterplan_compiler.outputs import atomic_write_bytes

    buf = io.BytesIO()
    fig.savefig(buf, format=Path(path).suffix.lstrip(".") or "png", metadata={"Software": None})
    atomic_write_bytes(path, buf.getvalue())  # a kill never leaves half a picture
    plt.close(fig)
    return path
