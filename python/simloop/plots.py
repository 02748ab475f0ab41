"""Pictures of a run (matplotlib, drawn off-screen to PNG); a sweep's are in
sweep_plots.py.

Both read the CSV files the commands write, so `sim_loop --plot` (which calls
`python -m simloop plot`) and `python -m simloop --plot` draw the same chart.
`trajectory_png(..., compare=[other csv])` draws several runs on the same
axes (the baseline against Break It, say).
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Iterable, Optional, Tuple, Union

PathLike = Union[str, "os.PathLike[str]"]

BOX_COLOR = "#d94c40"  # the scene's colours
PUSHER_COLOR = "#4073d9"
CONTACT_COLOR = "#555555"
# Runs after the first, when comparing: one colour per run.
RUN_COLORS = ["#d94c40", "#1b7f79", "#8a4fbf", "#c98a00"]
# A scenario's bodies, one colour each (the chapter's two first); its runs
# after the first, when comparing, one line style each.
BODY_COLORS = ["#d94c40", "#4073d9", "#1b7f79", "#8a4fbf", "#c98a00", "#555555", "#e377c2", "#17becf"]
RUN_STYLES = ["-", "--", ":", "-."]
REST_Z = 0.05  # the box's centre at rest, m
# The z axis a sound run and Break It share: fixed, widened only if a run
# leaves it (autoscaled, 3 mm of contact softness looks as wild as a hop).
Z_RANGE = (0.04, 0.12)


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
    if not rows:  # (every figure reads a last row)
        raise ValueError("no rows after the header: nothing to draw")
    table = np.array(rows, dtype=float).reshape(len(rows), len(names))
    return {name: table[:, i] for i, name in enumerate(names)}


def _save_and_close(fig, png: Path) -> Path:
    """Writes a new file beside png (exclusively: never through a planted link), renamed onto it when whole."""
    temp = None
    try:
        fd, temp = tempfile.mkstemp(prefix="." + png.name + ".", suffix=".tmp", dir=png.parent)
        with os.fdopen(fd, "wb") as out:
            fig.savefig(out, format="png", dpi=110)
        os.replace(temp, png)
    finally:
        _pyplot().close(fig)
        if temp is not None and os.path.lexists(temp):
            os.unlink(temp)
    return png


def _shove_window(cols):
    """(first step, last step + 1, force) of the shove, or None."""
    import numpy as np

    shove = np.nan_to_num(cols["shove_y"])
    acting = np.flatnonzero(shove != 0.0)
    if not acting.size:
        return None
    return acting[0], min(acting[-1] + 1, len(shove) - 1), shove[acting[0]]


def describe_run(cols, name: str = "") -> str:
    """'name: 2000 steps of 0.002 s, shove +7.0 N' from a trajectory's columns."""
    window = _shove_window(cols)
    text = _steps_of(cols) + (f", shove {window[2]:+.1f} N in y" if window else ", no shove")
    return f"{name}: {text}" if name else text


def _steps_of(cols) -> str:
    """'2000 steps of 0.002 s'."""
    return f"{int(cols['step'][-1])} steps of {_timestep(cols):.4g} s"


def _timestep(cols) -> float:
    steps = cols["step"][-1]
    return float(cols["time"][-1] / steps) if steps else float("nan")


def trajectory_png(csv: PathLike, png: PathLike, compare: Iterable[PathLike] = (), x: str = "auto") -> Path:
    """Draws trajectory_figure(csv, compare, x) into `png`."""
    return _save_and_close(trajectory_figure(csv, compare, x), Path(png))


def _scenario_metrics(csv: Path) -> Optional[dict]:
    """The metrics.json beside a scenario's trajectory.csv (it names the
    recorded bodies and the disturbances as they ran), or None for the chapter's."""
    try:
        metrics = json.loads((csv.parent / "metrics.json").read_text())
    except (OSError, ValueError):
        return None
    return metrics if isinstance(metrics, dict) and "bodies" in metrics else None


def _x_axis(runs, x: str) -> Tuple[str, list]:
    """The x axis to draw against, and the runs' distinct timesteps."""
    if x not in ("auto", "time", "step"):
        raise ValueError(f"x must be 'auto', 'time' or 'step', got {x!r}")
    timesteps = sorted({round(_timestep(run[0]), 12) for run in runs})
    if x == "auto":  # the axis the runs line up on: time when they span the same sim time
        spans = [float(run[0]["time"][-1]) for run in runs]
        x = "time" if max(spans) - min(spans) <= 1e-6 * max(max(spans), 1.0) + max(timesteps) else "step"
    return x, timesteps


def _x_label(x: str, timesteps: list) -> str:
    if x == "time":
        return "sim time (s)"
    if len(timesteps) > 1:
        return "step (the runs' timesteps differ: " + " s, ".join(f"{t:g}" for t in timesteps) + " s)"
    return "step"


def trajectory_figure(csv: PathLike, compare: Iterable[PathLike] = (), x: str = "auto"):
    """The run against time: x of the pusher and the box, the box's y and z,
    and the contact count; the shove's window shaded. A scenario's run (its
    metrics.json names its bodies) gets scenario_trajectory_figure instead.

    compare: other trajectory.csv files, drawn on the same axes (each run in
    its own colour; the box solid, the pusher dashed). x: "time" (sim
    seconds), "step" (step index), or "auto": time, unless the runs span
    different sim times (the baseline's 4 s beside Break It's 100 s), then step.
    """
    import numpy as np
    from matplotlib.lines import Line2D

    paths = [Path(csv), *[Path(c) for c in compare]]
    scenarios = [_scenario_metrics(p) for p in paths]
    if any(m is not None for m in scenarios):
        if not all(m is not None for m in scenarios):
            chapter = next(p for p, m in zip(paths, scenarios) if m is None)
            raise ValueError(f"{chapter.parent} is the chapter's run and the others a scenario's: draw them apart")
        return scenario_trajectory_figure([(_read_csv(p), p.parent.name, m) for p, m in zip(paths, scenarios)], x)
    runs = [(_read_csv(p), p.parent.name) for p in paths]
    comparing = len(runs) > 1
    x, timesteps = _x_axis(runs, x)
    fig, axes = _figure([1.1, 1, 1.2, 0.7], (9, 9))
    ax_x, ax_y, ax_z, ax_c = axes
    legend: list = []  # one legend for the figure, above the axes: never on the data
    z_low, z_high = Z_RANGE
    for k, (cols, name) in enumerate(runs):
        t = cols["time"] if x == "time" else cols["step"]
        box_color = RUN_COLORS[k % len(RUN_COLORS)] if comparing else BOX_COLOR
        pusher_color = box_color if comparing else PUSHER_COLOR
        shade = box_color if comparing else PUSHER_COLOR
        ax_x.plot(t, cols["box_x"], color=box_color, lw=1.4)
        ax_x.plot(t, cols["pusher_x"], color=pusher_color, lw=1.2, ls="--")
        ax_y.plot(t, cols["box_y"], color=box_color, lw=1.4)
        ax_z.plot(t, cols["box_z"], color=box_color, lw=1.2)
        ax_c.step(
            t,
            cols["ncon"],
            where="post",
            color=box_color if comparing else CONTACT_COLOR,
            lw=1.0,
            alpha=0.8 if comparing else 1.0,
        )
        if comparing:
            legend.append((Line2D([], [], color=box_color, lw=2), describe_run(cols, name)))
        window = _shove_window(cols)
        if window:
            first, last, force = window
            label = (f"{name}: " if comparing else "") + f"shove {force:+.1f} N in y"
            legend.append(_shade(axes, t, first, last, shade, label))
        z = cols["box_z"]
        finite = z[np.isfinite(z)]
        if finite.size:
            z_low, z_high = min(z_low, finite.min() - 0.005), max(z_high, finite.max() + 0.005)
            peak = int(np.nanargmax(z))
            ax_z.plot(t[peak], z[peak], "o", color=box_color, ms=5)
            right_half = t[peak] > (t[0] + t[-1]) / 2  # label towards the middle, inside the axes
            ax_z.annotate(
                f"peak {z[peak]:.4f} m, step {int(cols['step'][peak])}",
                (t[peak], z[peak]),
                xytext=(-6 if right_half else 6, 6 + 12 * k),
                textcoords="offset points",
                fontsize=8,
                color=box_color,
                ha="right" if right_half else "left",
            )
    if comparing:
        legend += [(Line2D([], [], color="black", lw=1.4), "box"), (Line2D([], [], color="black", ls="--"), "pusher")]
    else:
        legend = [
            (Line2D([], [], color=BOX_COLOR, lw=1.4), "box"),
            (Line2D([], [], color=PUSHER_COLOR, ls="--"), "pusher"),
        ] + legend
    legend.append((Line2D([], [], color="grey", lw=0.8, ls=":"), "box at rest (z 0.05 m)"))
    ax_z.axhline(REST_Z, color="grey", lw=0.8, ls=":")
    ax_z.set_ylim(z_low, z_high)
    ax_x.set_ylabel("x (m)")
    ax_y.set_ylabel("box y (m)\nsideways")
    ax_z.set_ylabel("box z (m)\nheight of its centre")
    _label_axes(axes, ax_c, x, timesteps)
    title = "ch0.1-sim-loop: " + (" against ".join(name for _, name in runs) if comparing else describe_run(runs[0][0]))
    return _titled(fig, title, legend, anchor=0.955, row_height=0.022)


def scenario_trajectory_figure(runs, x: str = "auto"):
    """Any scene's run against time, from its trajectory.csv and metrics.json:
    each recorded body's x, y and z and its speed, the contact count, and each
    disturbance's window shaded in its body's colour.

    runs: (columns, name, metrics) per run; runs after the first are drawn on
    the same axes, dashed, dotted, ... (a body keeps its colour). x: as in
    trajectory_figure.
    """
    import numpy as np
    from matplotlib.lines import Line2D

    x, timesteps = _x_axis(runs, x)
    bodies: list = []  # in the first run's column order; a body any run recorded
    for cols, _, metrics in runs:
        bodies += [
            b
            for b in sorted(
                metrics["bodies"], key=lambda b: list(cols).index(f"{b}_x") if f"{b}_x" in cols else len(cols)
            )
            if b not in bodies
        ]
    if not bodies:
        raise ValueError("the run recorded no bodies ([record] bodies = [...] in the scenario): no positions to draw")
    palette = BODY_COLORS if len(bodies) <= len(BODY_COLORS) else _many_colours(len(bodies))
    colour = {b: palette[i % len(palette)] for i, b in enumerate(bodies)}
    # A scenario's own count (its row's state's), or the chapter's ncon.
    counted = [next((c for c in ("contacts", "ncon") if c in cols), None) for cols, _, _ in runs]
    contacts = any(counted)
    ratios = [1, 1, 1, 1] + ([0.6] if contacts else [])
    fig, axes = _figure(ratios, (10, 2.0 * sum(ratios) + 1.6))
    ax_pos, ax_v = axes[:3], axes[3]
    legend: list = []
    for k, (cols, name, metrics) in enumerate(runs):
        t = cols["time"] if x == "time" else cols["step"]
        style = RUN_STYLES[k % len(RUN_STYLES)]
        for b in bodies:
            if f"{b}_x" not in cols:
                continue
            for ax, axis in zip(ax_pos, "xyz"):
                ax.plot(t, cols[f"{b}_{axis}"], color=colour[b], ls=style, lw=1.3)
            if all(f"{b}_v{axis}" in cols for axis in "xyz"):
                speed = np.sqrt(sum(cols[f"{b}_v{axis}"] ** 2 for axis in "xyz"))
                ax_v.plot(t, speed, color=colour[b], ls=style, lw=1.3)
        if counted[k]:
            axes[4].step(t, cols[counted[k]], where="post", color=CONTACT_COLOR, ls=style, lw=1.0)
        if len(runs) > 1:
            legend.append((Line2D([], [], color="black", ls=style), f"{name}: {_describe_scenario(cols, metrics)}"))
        for d in metrics.get("disturbances", []):
            first, steps = int(d["start_step"]), int(d["steps"])
            if steps <= 0 or first >= len(t):
                continue
            force = ", ".join(f"{v:+.2f}" for v in d["force"])
            torque = ", ".join(f"{v:+.2f}" for v in d["torque"])
            torque = f", [{torque}] N m" if any(d["torque"]) else ""
            label = (f"{name}: " if len(runs) > 1 else "") + f"disturbance on {d['body']}: [{force}] N{torque}"
            shade = colour.get(d["body"], CONTACT_COLOR)
            legend.append(_shade(axes, t, first, min(first + steps, len(t) - 1), shade, label))
    legend = [(Line2D([], [], color=colour[b], lw=2), b) for b in bodies] + legend
    for ax, axis in zip(ax_pos, "xyz"):
        ax.set_ylabel(f"{axis} (m)")
    ax_v.set_ylabel("speed (m/s)")
    _label_axes(axes, axes[4] if contacts else None, x, timesteps)
    cols, name, metrics = runs[0]
    title = f"scenario {metrics.get('scenario', name)}: " + (
        " against ".join(n for _, n, _ in runs) if len(runs) > 1 else _describe_scenario(cols, metrics)
    )
    return _titled(fig, title, legend, anchor=0.96, row_height=0.018)


def _figure(ratios: list, size: Tuple[float, float]):
    """A figure of len(ratios) panels, stacked on one x axis, of these heights."""
    return _pyplot().subplots(len(ratios), 1, sharex=True, figsize=size, gridspec_kw={"height_ratios": ratios})


def _shade(axes, t, first: int, last: int, colour, label: str) -> tuple:
    """Shades steps first to last on every panel (a shove's, a disturbance's
    window) and gives its legend entry: the label with those steps."""
    from matplotlib.patches import Patch

    for ax in axes:
        ax.axvspan(t[first], t[last], color=colour, alpha=0.15)
    return Patch(color=colour, alpha=0.3), f"{label}, steps {first} to {last - 1}"


def _label_axes(axes, contacts, x: str, timesteps: list) -> None:
    """The contacts panel's label and whole-number ticks, the x axis's label, every panel's grid."""
    from matplotlib.ticker import MaxNLocator

    if contacts is not None:
        contacts.set_ylabel("contacts")
        contacts.yaxis.set_major_locator(MaxNLocator(nbins=4, integer=True))  # a count: no 7.5 contacts
    axes[-1].set_xlabel(_x_label(x, timesteps))
    for ax in axes:
        ax.grid(alpha=0.3)


def _many_colours(count: int) -> list:
    """Distinct colours for more bodies than BODY_COLORS has: matplotlib's tab20, then its
    tab20b and tab20c (60 in all; a humanoid's 21 bodies each get their own)."""
    from matplotlib import colormaps

    colours = [colormaps[name](i) for name in ("tab20", "tab20b", "tab20c") for i in range(20)]
    return colours[: max(count, 1)]


def _describe_scenario(cols, metrics) -> str:
    """'1000 steps of 0.002 s, seed 0' (no disturbance: 'no disturbance')."""
    text = f"{_steps_of(cols)}, seed {metrics.get('seed', '?')}"
    return text if metrics.get("disturbances") else text + ", no disturbance"


def _titled(fig, title: str, legend: list, anchor: float, row_height: float):
    """The title, and one legend in two columns above the axes (never on the
    data), the axes laid out below it (row_height: one legend row's share of
    the figure's height)."""
    import textwrap

    fig.suptitle(title)
    handles = [handle for handle, _ in legend]
    # Long labels (a disturbance's force and torque) wrapped to half the
    # figure's width, so that neither column runs off its edge.
    labels = [textwrap.fill(label, 68, subsequent_indent="    ") for _, label in legend]
    lines = [label.count("\n") + 1 for label in labels]
    half = (len(labels) + 1) // 2  # matplotlib fills the first column first
    rows = max(sum(lines[:half]), sum(lines[half:]))
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, anchor), ncol=2, frameon=False, fontsize=8)
    fig.tight_layout(rect=(0, 0, 1, anchor + 0.035 - row_height * rows))
    return fig
