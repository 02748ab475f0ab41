"""Pictures of a run and of a sweep (matplotlib, drawn off-screen to PNG).

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
# The sweep's z panel: the stable band (-1 mm, +5 mm) and a little around it;
# points beyond are drawn on the edge, with their values.
SWEEP_Z_RANGE = (0.040, 0.066)
# The chapter's two timesteps, and its runs' length (2000 steps at either):
# a sweep runs each timestep for the same sim time, so its 0.05 s point is
# Break It's timestep, not Break It's run, and is labelled so.
CHAPTER_TIMESTEPS = ((0.002, "the chapter's 0.002 s"), (0.05, "Break It's 0.05 s"))
CHAPTER_STEPS = 2000


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
    steps = int(cols["step"][-1])
    dt = _timestep(cols)
    window = _shove_window(cols)
    shove = f"shove {window[2]:+.1f} N in y" if window else "no shove"
    text = f"{steps} steps of {dt:.4g} s, {shove}"
    return f"{name}: {text}" if name else text


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
    from matplotlib.patches import Patch

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
    plt = _pyplot()
    fig, (ax_x, ax_y, ax_z, ax_c) = plt.subplots(
        4, 1, sharex=True, figsize=(9, 9), gridspec_kw={"height_ratios": [1.1, 1, 1.2, 0.7]}
    )
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
            for ax in (ax_x, ax_y, ax_z, ax_c):
                ax.axvspan(t[first], t[last], color=shade, alpha=0.15)
            legend.append(
                (
                    Patch(color=shade, alpha=0.3),
                    (f"{name}: " if comparing else "") + f"shove {force:+.1f} N in y, steps {first} to {last - 1}",
                )
            )
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
    ax_c.set_ylabel("contacts")
    from matplotlib.ticker import MaxNLocator

    ax_c.yaxis.set_major_locator(MaxNLocator(nbins=4, integer=True))  # a count: no 7.5 contacts
    ax_c.set_xlabel(_x_label(x, timesteps))
    for ax in (ax_x, ax_y, ax_z, ax_c):
        ax.grid(alpha=0.3)
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
    from matplotlib.patches import Patch
    from matplotlib.ticker import MaxNLocator

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
    plt = _pyplot()
    ratios = [1, 1, 1, 1] + ([0.6] if contacts else [])
    fig, axes = plt.subplots(
        len(ratios), 1, sharex=True, figsize=(10, 2.0 * sum(ratios) + 1.6), gridspec_kw={"height_ratios": ratios}
    )
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
            last = min(first + steps, len(t) - 1)
            shade = colour.get(d["body"], CONTACT_COLOR)
            for ax in axes:
                ax.axvspan(t[first], t[last], color=shade, alpha=0.15)
            force = ", ".join(f"{v:+.2f}" for v in d["force"])
            torque = ", ".join(f"{v:+.2f}" for v in d["torque"])
            torque = f", [{torque}] N m" if any(d["torque"]) else ""
            legend.append(
                (
                    Patch(color=shade, alpha=0.3),
                    (f"{name}: " if len(runs) > 1 else "")
                    + f"disturbance on {d['body']}: [{force}] N{torque}, steps {first} to {last - 1}",
                )
            )
    legend = [(Line2D([], [], color=colour[b], lw=2), b) for b in bodies] + legend
    for ax, axis in zip(ax_pos, "xyz"):
        ax.set_ylabel(f"{axis} (m)")
    ax_v.set_ylabel("speed (m/s)")
    if contacts:
        axes[4].set_ylabel("contacts")
        axes[4].yaxis.set_major_locator(MaxNLocator(nbins=4, integer=True))  # a count: no 7.5 contacts
    axes[-1].set_xlabel(_x_label(x, timesteps))
    for ax in axes:
        ax.grid(alpha=0.3)
    cols, name, metrics = runs[0]
    title = f"scenario {metrics.get('scenario', name)}: " + (
        " against ".join(n for _, n, _ in runs) if len(runs) > 1 else _describe_scenario(cols, metrics)
    )
    return _titled(fig, title, legend, anchor=0.96, row_height=0.018)


def _many_colours(count: int) -> list:
    """Distinct colours for more bodies than BODY_COLORS has: matplotlib's tab20, then its
    tab20b and tab20c (60 in all; a humanoid's 21 bodies each get their own)."""
    from matplotlib import colormaps

    colours = [colormaps[name](i) for name in ("tab20", "tab20b", "tab20c") for i in range(20)]
    return colours[: max(count, 1)]


def _describe_scenario(cols, metrics) -> str:
    """'1000 steps of 0.002 s, seed 0' (no disturbance: 'no disturbance')."""
    text = f"{int(cols['step'][-1])} steps of {_timestep(cols):.4g} s, seed {metrics.get('seed', '?')}"
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


def _mark_off_scale(ax, xs, values, low, high, color):
    """Draws points beyond [low, high] on the edge, as arrows, with their values."""
    for x, v in zip(xs, values):
        if low <= v <= high:
            continue
        above = v > high
        edge = high if above else low
        ax.plot(x, edge, "^" if above else "v", color=color, ms=7, clip_on=False, zorder=5)
        ax.annotate(
            f"{v:.3g}",
            (x, edge),
            xytext=(0, -9 if above else 9),
            textcoords="offset points",
            rotation=90,
            fontsize=7,
            color=color,
            ha="center",
            va="top" if above else "bottom",
        )


def sweep_png(csv: PathLike, png: PathLike) -> Path:
    """Draws sweep_figure(csv) into `png`."""
    return _save_and_close(sweep_figure(csv), Path(png))


def sweep_figure(csv: PathLike):
    """The sweep's figures against the timestep (log scale): z zoomed on the
    stable band with the far points marked on its edges, the edge, the
    chapter's 0.002 s and 0.05 s, sideways drift, and the energy audit. A
    scenario sweep's sweep.csv (it has a blew_up column) gets
    scenario_sweep_figure instead."""
    import numpy as np

    cols = _read_csv(Path(csv))
    if "blew_up" in cols:
        return scenario_sweep_figure(cols)
    plt = _pyplot()
    dt = cols["timestep"]
    stable = cols["stable"] == 1
    edge = dt[np.flatnonzero(np.cumprod(stable))[-1]] if stable[0] else None
    fig, axes = plt.subplots(3, 1, sharex=True, figsize=(10, 8.5), gridspec_kw={"height_ratios": [1.6, 1, 1]})
    ax_z, ax_y, ax_e = axes
    low, high = SWEEP_Z_RANGE
    peak, final = cols["peak_box_z"], cols["final_box_z"]
    ax_z.axhspan(REST_Z - 0.001, REST_Z + 0.005, color="green", alpha=0.12, label="stable band\n(-1 mm, +5 mm)")
    ax_z.axhline(REST_Z, color="grey", lw=0.8, ls="--")
    ax_z.plot(dt, np.clip(peak, low, high), "o-", color=BOX_COLOR, ms=4, label="peak z")
    ax_z.plot(dt, np.clip(final, low, high), "s--", color="#7a3b35", ms=3, label="final z")
    _mark_off_scale(ax_z, dt, peak, low, high, BOX_COLOR)
    _mark_off_scale(ax_z, dt, final, low, high, "#7a3b35")
    ax_z.plot([], [], "v", color="grey", label="off the scale\n(value in m)")
    ax_z.set_ylim(low, high)
    ax_z.set_ylabel("box centre z (m)")
    ax_y.plot(dt, cols["max_abs_box_y"], "o-", color=PUSHER_COLOR, ms=3, label="largest |y|")
    ax_y.set_ylabel("largest |y| (m)")
    ax_e.plot(dt, cols["work_constraint_positive"], "o-", color="#b5651d", ms=3, label="contacts'\npositive work")
    ax_e.plot(dt, cols["energy_unexplained"], "o-", color="#555555", ms=3, label="unexplained\nby any force")
    ax_e.axhline(0.0, color="grey", lw=0.8)
    ax_e.set_yscale("symlog", linthresh=0.01)
    ax_e.set_ylabel("energy over the run (J)")
    ax_e.set_xlabel("timestep (s, log scale)")
    for ax in axes:
        ax.set_xscale("log")
        ax.grid(alpha=0.3, which="both")
        for x in dt[~stable]:
            ax.axvline(x, color=BOX_COLOR, alpha=0.07, lw=6)
        if edge is not None:
            ax.axvline(edge, color="black", lw=1.2, ls=":", label=f"edge: {edge:.4g} s" if ax is ax_z else None)
        for x, name in CHAPTER_TIMESTEPS:
            ax.axvline(x, color="#2a6f2a", lw=1.0, ls="-.", alpha=0.8)
            steps = cols["steps"][np.isclose(dt, x, rtol=1e-12)]
            if len(steps) and steps[0] != CHAPTER_STEPS:
                name += f"\n{steps[0]:.0f} steps, not {CHAPTER_STEPS}"
            if ax is ax_z:  # named above the panel, clear of the off-scale values
                ax.annotate(
                    name,
                    (x, 1.0),
                    xycoords=("data", "axes fraction"),
                    xytext=(0, 3),
                    textcoords="offset points",
                    fontsize=8,
                    color="#2a6f2a",
                    ha="center",
                    va="bottom",
                )
    ax_z.plot([], [], color="#2a6f2a", ls="-.", label="the chapter's\ntimesteps")
    ax_z.plot([], [], color=BOX_COLOR, alpha=0.25, lw=6, label="unstable")
    for ax in axes:  # legends beside the axes, never on the data
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    title = f"Break It, swept: largest stable timestep {edge:.4g} s" if edge is not None else "no stable timestep"
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def scenario_sweep_figure(cols):
    """A scenario sweep against the timestep (log scale): each recorded body's
    distance from where the finest timestep left it, with the tolerance; the
    largest speed any recorded body reached; the timesteps that blew up
    shaded (warnings marked), and the edge."""
    import numpy as np

    plt = _pyplot()
    dt = cols["timestep"]
    blew_up = cols["blew_up"] == 1
    edge = dt[np.flatnonzero(np.cumprod(~blew_up))[-1]] if not blew_up[0] else None
    warned = (cols["mujoco_warnings"] > 0) | (cols["diverged"] > 0)
    bodies = [name[: -len("_offset")] for name in cols if name.endswith("_offset") and name != "max_offset"]
    fig, (ax_off, ax_v) = plt.subplots(2, 1, sharex=True, figsize=(10, 7), gridspec_kw={"height_ratios": [1.4, 1]})
    floor = cols["tolerance"][0] * 1e-3  # the reference's own zero, drawn at the bottom of the log axis
    for i, body in enumerate(bodies):
        offset = np.where(np.isfinite(cols[body + "_offset"]), cols[body + "_offset"], np.nan)
        ax_off.plot(
            dt[1:], np.maximum(offset[1:], floor), "o-", ms=4, color=RUN_COLORS[i % len(RUN_COLORS)], label=body
        )
    ax_off.axhline(
        cols["tolerance"][0], color="black", lw=1.0, ls="--", label=f"tolerance\n({cols['tolerance'][0]:.3g} m)"
    )
    ax_off.set_yscale("log")
    ax_off.set_ylabel("final position's distance\nfrom the finest timestep's (m)")
    ax_v.plot(dt, cols["peak_speed"], "o-", ms=4, color=CONTACT_COLOR, label="largest speed\nof a recorded body")
    ax_v.plot(
        dt[warned], cols["peak_speed"][warned], "x", ms=9, color=BOX_COLOR, label="warned (MuJoCo or\nsimloop_DIVERGED)"
    )
    ax_v.set_yscale("log")
    ax_v.set_ylabel("largest speed (m/s)")
    ax_v.set_xlabel("timestep (s, log scale)")
    for ax in (ax_off, ax_v):
        ax.set_xscale("log")
        ax.grid(alpha=0.3, which="both")
        for x in dt[blew_up]:
            ax.axvline(x, color=BOX_COLOR, alpha=0.07, lw=6)
        if edge is not None:
            ax.axvline(edge, color="black", lw=1.2, ls=":", label=f"edge: {edge:.4g} s" if ax is ax_off else None)
        ax.axvline(
            dt[0],
            color="#2a6f2a",
            lw=1.0,
            ls="-.",
            label=f"reference: {dt[0]:.4g} s\n(the finest)" if ax is ax_off else None,
        )
    ax_off.plot([], [], color=BOX_COLOR, alpha=0.25, lw=6, label="blew up")
    for ax in (ax_off, ax_v):  # legends beside the axes, never on the data
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    title = (
        f"scenario swept: largest timestep before any blew up {edge:.4g} s"
        if edge is not None
        else "scenario swept: even the finest timestep blew up"
    )
    fig.suptitle(title)
    fig.tight_layout()
    return fig
