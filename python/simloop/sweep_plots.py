"""Pictures of a sweep (matplotlib, drawn off-screen to PNG): the chapter's
sweep.csv and a scenario sweep's, against the timestep."""

from __future__ import annotations

from pathlib import Path

from .plots import (
    BOX_COLOR,
    CONTACT_COLOR,
    PUSHER_COLOR,
    REST_Z,
    RUN_COLORS,
    PathLike,
    _pyplot,
    _read_csv,
    _save_and_close,
)

# The sweep's z panel: the stable band (-1 mm, +5 mm) and a little around it;
# points beyond are drawn on the edge, with their values.
SWEEP_Z_RANGE = (0.040, 0.066)
# The chapter's two timesteps, and its runs' length (2000 steps at either):
# a sweep runs each timestep for the same sim time, so its 0.05 s point is
# Break It's timestep, not Break It's run, and is labelled so.
CHAPTER_TIMESTEPS = ((0.002, "the chapter's 0.002 s"), (0.05, "Break It's 0.05 s"))
CHAPTER_STEPS = 2000


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
