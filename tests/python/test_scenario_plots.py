"""--plot for any scene: each recorded body's position and speed, the
contacts, the disturbance windows shaded, from trajectory.csv and metrics.json."""

import json
import subprocess
import sys

import numpy as np
from conftest import ROOT, run_command, sim_loop_exe

PUSHT = ROOT / "tests" / "scenes" / "pusht.toml"


def test_both_commands_plot_a_scenarios_run(tmp_path):
    env = {"SIMLOOP_PYTHON": sys.executable, "PATH": "/usr/bin:/bin"}  # sim_loop draws through this Python
    flags = ["--scenario", str(PUSHT), "--no-rerun", "--plot", "--out", "o"]
    for name, cmd in (("py", [sys.executable, "-m", "simloop"]), ("cpp", [str(sim_loop_exe())])):
        (tmp_path / name).mkdir()
        proc = subprocess.run(
            cmd + flags,
            cwd=tmp_path / name,
            capture_output=True,
            text=True,
            env=env,
            stdin=subprocess.DEVNULL,
            timeout=120,
        )
        assert proc.returncode == 0, proc.stderr
        assert (tmp_path / name / "o" / "trajectory.png").read_bytes()[:4] == b"\x89PNG"
        assert "plot: o/trajectory.png" in proc.stdout


def _span(patch):
    """(left, right) of an axvspan: a Rectangle on matplotlib 3.9+, a Polygon before."""
    if hasattr(patch, "get_width"):
        return patch.get_x(), patch.get_x() + patch.get_width()
    xs = patch.get_xy()[:, 0]
    return min(xs), max(xs)


def _scenario_run(tmp_path, folder, *flags):
    proc = run_command(["--scenario", str(PUSHT), "--no-rerun", "--out", folder, *flags], tmp_path)
    assert proc.returncode == 0, proc.stderr
    return tmp_path / folder


def test_the_picture_draws_each_body_its_speed_the_contacts_and_the_disturbance(tmp_path):
    from simloop import plots

    out = _scenario_run(tmp_path, "o")
    cols = plots._read_csv(out / "trajectory.csv")
    metrics = json.loads((out / "metrics.json").read_text())
    fig = plots.trajectory_figure(out / "trajectory.csv")
    try:
        ax_x, ax_y, ax_z, ax_v, ax_c = fig.axes
        for ax, axis in ((ax_x, "x"), (ax_y, "y"), (ax_z, "z")):
            drawn = [line.get_ydata() for line in ax.get_lines()]
            assert len(drawn) == 2  # tblock and pusher, nothing else
            for body in ("tblock", "pusher"):
                assert any(np.array_equal(d, cols[f"{body}_{axis}"]) for d in drawn), (axis, body)
        speed = np.sqrt(cols["tblock_vx"] ** 2 + cols["tblock_vy"] ** 2 + cols["tblock_vz"] ** 2)
        assert any(np.allclose(line.get_ydata(), speed) for line in ax_v.get_lines())
        assert np.array_equal(ax_c.get_lines()[0].get_ydata(), cols["contacts"])
        # The disturbance as it ran (metrics.json), shaded on every panel, from its first step's time.
        (bump,) = metrics["disturbances"]
        start = cols["time"][bump["start_step"]]
        end = cols["time"][bump["start_step"] + bump["steps"]]
        for ax in fig.axes:
            spans = [_span(patch) for patch in ax.patches]
            assert any(abs(low - start) < 1e-12 and abs(high - end) < 1e-12 for low, high in spans), ax.get_ylabel()
        labels = [t.get_text() for t in fig.legends[0].get_texts()]
        assert labels[:2] == ["tblock", "pusher"]
        assert (
            f"disturbance on tblock: [+0.00, {bump['force'][1]:+.2f}, +0.00] N, steps {bump['start_step']} to "
            f"{bump['start_step'] + bump['steps'] - 1}" in labels
        )
        assert "scenario pusht: 1000 steps of 0.002 s, seed 0" in fig._suptitle.get_text()
    finally:
        plots._pyplot().close(fig)


def test_two_scenario_runs_on_the_same_axes(tmp_path):
    _scenario_run(tmp_path, "seed0")
    _scenario_run(tmp_path, "seed1", "--seed", "1")
    proc = run_command(["plot", "trajectory", "--out", "seed0", "--compare", "seed1"], tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "plot: seed0/trajectory_vs_seed1.png\n"
    from simloop import plots

    fig = plots.trajectory_figure(tmp_path / "seed0" / "trajectory.csv", [tmp_path / "seed1" / "trajectory.csv"])
    try:
        styles = {line.get_linestyle() for line in fig.axes[0].get_lines()}
        assert styles == {"-", "--"}  # a body keeps its colour; the second run is dashed
        labels = [t.get_text() for t in fig.legends[0].get_texts()]
        assert any(label.startswith("seed1: 1000 steps of 0.002 s, seed 1") for label in labels), labels
    finally:
        plots._pyplot().close(fig)


def test_runs_at_two_timesteps_over_the_same_sim_time_line_up_in_time(tmp_path):
    """PushT's 2 s at 0.002 s and at 0.001 s: drawn against time, where they line up (against the step index
    the finer run would be stretched twice as wide); runs of different spans are drawn by step."""
    from simloop import plots

    _scenario_run(tmp_path, "coarse")
    _scenario_run(tmp_path, "fine", "--timestep", "0.001")
    _scenario_run(tmp_path, "short", "--steps", "300")
    same_span = plots.trajectory_figure(tmp_path / "coarse" / "trajectory.csv", [tmp_path / "fine" / "trajectory.csv"])
    other_span = plots.trajectory_figure(
        tmp_path / "coarse" / "trajectory.csv", [tmp_path / "short" / "trajectory.csv"]
    )
    try:
        assert same_span.axes[-1].get_xlabel() == "sim time (s)"
        assert other_span.axes[-1].get_xlabel() == "step"
        # Every legend entry fits inside the figure (long ones are wrapped).
        same_span.canvas.draw()
        width = same_span.bbox.width
        boxes = [t.get_window_extent() for t in same_span.legends[0].get_texts()]
        assert all(0 <= box.x0 and box.x1 <= width for box in boxes), [(b.x0, b.x1, width) for b in boxes]
    finally:
        plots._pyplot().close(same_span)
        plots._pyplot().close(other_span)


def test_a_scenario_beside_the_chapters_run_or_without_bodies_is_refused(tmp_path):
    _scenario_run(tmp_path, "pusht")
    assert run_command(["--smoke", "--no-rerun", "--out", "chapter"], tmp_path).returncode == 0
    mixed = run_command(["plot", "trajectory", "--out", "pusht", "--compare", "chapter"], tmp_path)
    assert mixed.returncode == 1 and len(mixed.stderr.splitlines()) == 1, mixed.stderr
    assert "chapter is the chapter's run and the others a scenario's: draw them apart" in mixed.stderr
    assert not list((tmp_path / "pusht").glob("*.png"))
    joints_only = tmp_path / "joints.toml"
    joints_only.write_text(
        PUSHT.read_text()
        .replace('scene = "pusht.xml"', f'scene = "{PUSHT.parent / "pusht.xml"}"')
        .replace('bodies = ["tblock", "pusher"]', "bodies = []")
    )
    proc = run_command(["--scenario", str(joints_only), "--no-rerun", "--plot", "--out", "j"], tmp_path)
    assert proc.returncode == 1 and "the run recorded no bodies" in proc.stderr, proc.stderr
    assert len(proc.stderr.splitlines()) == 1
    assert (tmp_path / "j" / "trajectory.csv").is_file()  # the run's outputs stay
