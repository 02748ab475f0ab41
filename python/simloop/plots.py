"""Pictures of a run and of a sweep (matplotlib, drawn off-screen to PNG).

Both read the CSV files the commands write, so `sim_loop --plot` (which calls
`python -m simloop plot`) and `python -m simloop --plot` draw the same chart.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Union

PathLike = Union[str, "os.PathLike[str]"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")  # files only: never a window
    import matplotlib.pyplot as plt

    return plt


def _read_csv(path: Path):
    import numpy as np

    with open(path) as f:
        names = f.readline().strip().split(",")
        rows = [[float(cell) if cell else np.nan for cell in line.rstrip("\n").split(",")] for line in f]
    table = np.array(rows, dtype=float).reshape(len(rows), len(names))
    return {name: table[:, i] for i, name in enumerate(names)}


def _save(fig, png: Path) -> Path:
    """Writes beside the destination, then renames: never a half-written PNG."""
    temp = png.with_name("." + png.name + ".tmp")
    fig.savefig(temp, format="png", dpi=110)
    os.replace(temp, png)
    return png


def trajectory_png(csv: PathLike, png: PathLike) -> Path:
    """Box y and z against time, the shove's window shaded."""
    import numpy as np

    cols = _read_csv(Path(csv))
    plt = _pyplot()
    time, y, z = cols["time"], cols["box_y"], cols["box_z"]
    shove = np.nan_to_num(cols["shove_y"])
    fig, (ax_y, ax_z) = plt.subplots(2, 1, sharex=True, figsize=(8, 5.5))
    for ax, values, label in ((ax_y, y, "box y (m): sideways"), (ax_z, z, "box z (m): height of its centre")):
        ax.plot(time, values, color="#d94c40", lw=1.4)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        acting = np.flatnonzero(shove != 0.0)
        if acting.size:
            ax.axvspan(time[acting[0]], time[min(acting[-1] + 1, len(time) - 1)], color="#4073d9", alpha=0.18,
                       label=f"shove {shove[acting[0]]:+.1f} N in y")
            ax.legend(loc="best", fontsize=8)
    ax_z.axhline(0.05, color="grey", lw=0.8, ls="--")
    ax_z.set_xlabel("sim time (s)")
    dt = time[1] - time[0] if len(time) > 1 else float("nan")
    fig.suptitle(f"ch0.1-sim-loop: the box, {int(cols['step'][-1])} steps of {dt:.4g} s")
    fig.tight_layout()
    out = _save(fig, Path(png))
    plt.close(fig)
    return out


def sweep_png(csv: PathLike, png: PathLike) -> Path:
    """The sweep's figures against the timestep (log scale), the edge marked."""
    import numpy as np

    cols = _read_csv(Path(csv))
    plt = _pyplot()
    dt = cols["timestep"]
    stable = cols["stable"] == 1
    edge = dt[np.flatnonzero(np.cumprod(stable))[-1]] if stable[0] else None
    fig, axes = plt.subplots(3, 1, sharex=True, figsize=(8, 8))
    ax_z, ax_y, ax_e = axes
    ax_z.plot(dt, cols["peak_box_z"], "o-", color="#d94c40", ms=3, label="peak z")
    ax_z.plot(dt, cols["final_box_z"], "s--", color="#7a3b35", ms=3, label="final z")
    ax_z.axhline(0.05, color="grey", lw=0.8, ls="--")
    ax_z.axhspan(0.049, 0.055, color="green", alpha=0.08, label="stable band (-1 mm, +5 mm)")
    ax_z.set_ylabel("box centre z (m)")
    ax_z.set_ylim(max(min(cols["final_box_z"].min(), 0.04) - 0.01, -0.2), max(cols["peak_box_z"].max() + 0.01, 0.07))
    ax_y.plot(dt, cols["max_abs_box_y"], "o-", color="#4073d9", ms=3)
    ax_y.set_ylabel("largest |y| (m)")
    ax_e.plot(dt, cols["work_constraint_positive"], "o-", color="#b5651d", ms=3, label="contacts' positive work")
    ax_e.plot(dt, cols["energy_unexplained"], "o-", color="#555555", ms=3, label="unexplained by any force")
    ax_e.axhline(0.0, color="grey", lw=0.8)
    ax_e.set_yscale("symlog", linthresh=0.01)
    ax_e.set_ylabel("energy over the run (J)")
    ax_e.set_xlabel("timestep (s, log scale)")
    for ax in axes:
        ax.set_xscale("log")
        ax.grid(alpha=0.3, which="both")
        for x in dt[~stable]:
            ax.axvline(x, color="#d94c40", alpha=0.06, lw=6)
        if edge is not None:
            ax.axvline(edge, color="black", lw=1.2, ls=":", label=f"edge: {edge:.4g} s" if ax is ax_z else None)
    ax_z.legend(loc="upper left", fontsize=8)
    ax_e.legend(loc="upper left", fontsize=8)
    title = f"Break It, swept: largest stable timestep {edge:.4g} s" if edge is not None else "no stable timestep"
    fig.suptitle(title)
    fig.tight_layout()
    out = _save(fig, Path(png))
    plt.close(fig)
    return out
