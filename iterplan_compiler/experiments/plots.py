"""Matplotlib figures in the layout of the paper's Fig. 3 (b)-(d).

Error bars are 3 SEM, as in the paper; the "ideal" curve is the minimum-distance duration at
constant speed.  Uses the non-interactive Agg backend, so it works without a display.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path

from iterplan_compiler.experiments.harness import Point
from iterplan_compiler.experiments.sweeps import Experiment

TITLES = {
    Experiment.FIG3B: "Ordered Patrol: loop time vs number of locations",
    Experiment.FIG3C: "Cover: overhead vs locations to cover (universe 713)",
    Experiment.FIG3D: "Cover of 61 locations: duration vs number of locations",
}
MARKERS = {"distance": "o", "last": "s", "random": "^", "tour": "D"}
#: The paper's numbers (Section "Runtime Overhead"), drawn into the figures.
PAPER_PATROL_700K_PCT = 88.0     # Ordered Patrol at 700,000 locations: at most +88 % over ideal
PAPER_COVER_PCT = 60.0           # Cover, distance sorter: near constant ~60 % overhead


def plot(experiment: Experiment, points: Sequence[Point], path: Path, note: str = "") -> Path:
    """Draw one experiment's figure to ``path`` (PNG), ``note`` (e.g. the vehicle) in the
    footnote; returns the path."""
    exp = experiment.value  # the points are CSV rows: their experiment is the value
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    pts = [p for p in points if p.experiment == exp and p.n > 0]
    # x: what the experiment varies.
    xof = (lambda p: p.count) if experiment is Experiment.FIG3C else (lambda p: p.universe)
    fig, ax = plt.subplots(figsize=(5.0, 3.6), dpi=120)
    for sorter in sorted({p.sorter for p in pts}):
        sp = sorted((p for p in pts if p.sorter == sorter), key=xof)
        if experiment is Experiment.FIG3C:
            ys, es = [p.overhead_pct for p in sp], [p.overhead_err3 for p in sp]
        elif experiment is Experiment.FIG3B:
            ys, es = [p.duration / 60.0 for p in sp], [p.duration_err3 / 60.0 for p in sp]
        else:
            ys, es = [p.duration / 60.0 for p in sp], [p.duration_err3 / 60.0 for p in sp]
        ax.errorbar([xof(p) for p in sp], ys, yerr=es, marker=MARKERS.get(sorter, "x"),
                    capsize=3, linestyle="-", label=sorter)
    if experiment is not Experiment.FIG3C and pts:
        ideal: dict[int, list[float]] = {}
        for p in pts:
            ideal.setdefault(xof(p), []).append(p.ideal)
        xs = sorted(ideal)
        ax.plot(xs, [sum(ideal[x]) / len(ideal[x]) / 60.0 for x in xs], "k--", label="ideal")
    if experiment is Experiment.FIG3C:
        ax.axhline(PAPER_COVER_PCT, color="0.4", linestyle=":", lw=1.2,
                   label=f"paper, distance (~{PAPER_COVER_PCT:g} %)")
    elif experiment is Experiment.FIG3B and pts:
        big = [p for p in pts if p.universe == max(q.universe for q in pts)]
        if big and big[0].universe >= 100_000:
            ref = big[0].ideal * (1 + PAPER_PATROL_700K_PCT / 100) / 60.0
            ax.plot([big[0].universe], [ref], marker="*", color="0.3", ms=10, linestyle="none",
                    label=f"paper at 700k (ideal +{PAPER_PATROL_700K_PCT:g} %)")
    if experiment is Experiment.FIG3C:
        ax.set_xlabel("locations to cover")
        ax.set_ylabel("overhead over ideal [%]")
    else:
        ax.set_xlabel("number of locations")
        ax.set_ylabel("loop time [min]" if experiment is Experiment.FIG3B else "cover time [min]")
        # fig3b on a linear axis, like the paper (its overhead grows linearly in the number
        # of locations); fig3d spans orders of magnitude and reads better on a log axis.
        if experiment is Experiment.FIG3D and pts and \
                max(xof(p) for p in pts) / max(1, min(xof(p) for p in pts)) > 50:
            ax.set_xscale("log")
        elif experiment is Experiment.FIG3B:
            from matplotlib.ticker import FuncFormatter

            ax.xaxis.set_major_formatter(FuncFormatter(
                lambda v, _pos: f"{v / 1000:g}k" if v >= 1000 else f"{v:g}"))
    ax.set_title(TITLES.get(experiment, exp), fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.text(0.01, 0.01, "error bars: 3 SEM" + (f"; {note}" if note else ""), fontsize=6)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    # No timestamp in PNG metadata: re-running gives the same file for the same data.
    from iterplan_compiler.outputs import atomic_write_bytes

    buf = io.BytesIO()
    fig.savefig(buf, format=Path(path).suffix.lstrip(".") or "png", metadata={"Software": None})
    atomic_write_bytes(path, buf.getvalue())  # a kill never leaves half a picture
    plt.close(fig)
    return path
