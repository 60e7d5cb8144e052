"""Mission results: the event log, track, photos and arrivals of a flown mission, the writers
of ``iterc run``'s output files (CSV, GeoJSON, JSON summary, PNG plot), and the paper's
"ideal" distance used by the summary."""

from __future__ import annotations

import csv
import io
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from iterplan_compiler.outputs import atomic_write_bytes, atomic_write_json, atomic_write_text
from iterplan_compiler.runtime.grid import GridMap
from iterplan_compiler.runtime.ideal import ideal_distance  # noqa: F401  (re-exported)


@contextmanager
def _atomic_csv(path: str | Path) -> Iterator[io.StringIO]:
    """A text buffer written to ``path`` atomically when the block ends (outputs.py)."""
    buf = io.StringIO(newline="")
    yield buf
    atomic_write_text(path, buf.getvalue())


@dataclass
class LogEntry:
    t: float
    kind: str          # "c" controllable, "u" uncontrollable, "v" vehicle, "p" planner, "x" note
    label: str
    state: int
    x: float
    y: float
    alt: float
    cell: int = -1


@dataclass
class MissionResult:
    ok: bool
    reason: str
    summary: dict
    log: list[LogEntry]
    track: np.ndarray                 # (k, 4): t, x, y, alt
    photos: list[tuple[float, int, float, float]]
    arrivals: list[tuple[float, int, float, float]]
    grid: GridMap
    counts: dict = field(default_factory=dict)

    # -- outputs ------------------------------------------------------------------------------
    def write_track_csv(self, path: str | Path) -> None:
        lat, lon = self.grid.to_latlon(self.track[:, 1], self.track[:, 2])
        with _atomic_csv(path) as fh:
            w = csv.writer(fh)
            w.writerow(["t", "lat", "lon", "alt", "east", "north"])
            for (t, x, y, a), la, lo in zip(self.track, np.atleast_1d(lat), np.atleast_1d(lon), strict=False):
                w.writerow([f"{t:.2f}", f"{la:.7f}", f"{lo:.7f}", f"{a:.1f}", f"{x:.2f}",
                            f"{y:.2f}"])

    def write_events_csv(self, path: str | Path) -> None:
        with _atomic_csv(path) as fh:
            w = csv.writer(fh)
            w.writerow(["t", "kind", "label", "state", "east", "north", "alt", "cell"])
            for e in self.log:
                w.writerow([f"{e.t:.2f}", e.kind, e.label, e.state, f"{e.x:.2f}", f"{e.y:.2f}",
                            f"{e.alt:.1f}", self.grid.cell_name(e.cell) if e.cell >= 0 else ""])

    def geojson(self) -> dict:
        """Track as a LineString, arrivals and photos as Points (lon, lat), summary as props."""
        lat, lon = self.grid.to_latlon(self.track[:, 1], self.track[:, 2])
        line = [[round(float(a), 7), round(float(b), 7)] for a, b in
                zip(np.atleast_1d(lon), np.atleast_1d(lat), strict=False)]
        feats = [{"type": "Feature", "properties": {"kind": "track", **self.summary},
                  "geometry": {"type": "LineString", "coordinates": line}}]
        for kind, rows in (("arrival", self.arrivals), ("photo", self.photos)):
            for t, cell, x, y in rows:
                la, lo = self.grid.to_latlon(x, y)
                feats.append({"type": "Feature",
                              "properties": {"kind": kind, "t": round(t, 2),
                                             "cell": self.grid.cell_name(cell)},
                              "geometry": {"type": "Point",
                                           "coordinates": [round(lo, 7), round(la, 7)]}})
        return {"type": "FeatureCollection", "features": feats}

    def write_geojson(self, path: str | Path) -> None:
        atomic_write_json(path, self.geojson(), indent=1)

    def write_summary(self, path: str | Path) -> None:
        atomic_write_json(path, self.summary, indent=2)

    def plot(self, path: str | Path) -> None:
        """PNG of the map (locations and sensor cells shaded), the flown track, arrivals and
        photos.  Cells are drawn as one image, so maps of 10^6 cells plot quickly."""
        import matplotlib  # lazy: the aircraft never needs it

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.colors import to_rgba
        from matplotlib.patches import Patch

        g = self.grid
        fig, ax = plt.subplots(figsize=(8, min(16.0, 8 * g.rows / max(g.cols, 1) + 0.5)),
                               dpi=100)
        img = np.ones((g.rows, g.cols, 4), dtype=np.float32)
        img[..., 3] = 0.0
        loc = np.zeros(g.num_cells, dtype=bool)
        loc[g.cells] = True
        img.reshape(-1, 4)[loc] = to_rgba("#eeeeee")
        colours = ["#f5a623", "#d0021b", "#4a90e2", "#7ed321", "#9013fe"]
        handles = []
        for i, (name, ids) in enumerate(sorted(g.sensors.items())):
            col = to_rgba(colours[i % len(colours)], 0.45)
            flat = img.reshape(-1, 4)
            # Blend over what is there, so overlapping sensor sets stay visible.
            flat[ids, :3] = flat[ids, :3] * (1 - col[3]) + np.asarray(col[:3]) * col[3]
            flat[ids, 3] = np.maximum(flat[ids, 3], 0.6)
            handles.append(Patch(color=col, label=name))
        ax.imshow(img, origin="lower", interpolation="nearest",
                  extent=(0, g.cols * g.cell_size, 0, g.rows * g.cell_size))
        ax.plot(self.track[:, 1], self.track[:, 2], "-", color="#333333", lw=0.8, label="track")
        if self.arrivals:
            a = np.asarray([(x, y) for _, _, x, y in self.arrivals])
            ax.plot(a[:, 0], a[:, 1], "o", ms=3, color="#4a90e2", label="arrived")
        if self.photos:
            p = np.asarray([(x, y) for _, _, x, y in self.photos])
            ax.plot(p[:, 0], p[:, 1], "*", ms=9, color="#d0021b", label="photo")
        ax.plot(*g.home, "k^", ms=8, label="home")
        ax.set_xlim(-g.cell_size, (g.cols + 1) * g.cell_size)
        ax.set_ylim(-g.cell_size, (g.rows + 1) * g.cell_size)
        ax.set_aspect("equal")
        ax.set_xlabel("east (m)")
        ax.set_ylabel("north (m)")
        s = self.summary
        oh = s.get("overhead_pct")
        ax.set_title(f"{g.name}: {s.get('duration_s', 0):.0f} s, {s.get('distance_m', 0):.0f} m, "
                     f"overhead {'n/a' if oh is None else f'{oh:.0f} %'}")
        ax.legend(handles=handles + ax.get_legend_handles_labels()[0], loc="upper right",
                  fontsize=7)
        fig.tight_layout()
        buf = io.BytesIO()
        fig.savefig(buf, format="png")
        atomic_write_bytes(path, buf.getvalue())
        plt.close(fig)
