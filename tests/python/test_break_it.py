"""Break It, measured: the sweep, the energy audit, the pictures."""

import subprocess
import sys

import numpy as np
import pytest
import simloop
from conftest import run_command, sim_loop_exe
from expected import expected


def test_audit_columns_and_totals():
    result = simloop.run(audit_energy=True)
    assert result.column_names == simloop.COLUMN_NAMES + simloop.ENERGY_COLUMN_NAMES
    assert result.trajectory.shape == (2001, 29)
    energy = result.energy
    unexplained = result.column("energy_unexplained")
    assert unexplained[-1] == pytest.approx(energy["unexplained"], abs=1e-12)
    work = sum(result.column(c) for c in ("work_actuator", "work_shove", "work_passive", "work_constraint"))
    np.testing.assert_allclose(unexplained, result.column("energy") - result.column("energy")[0] - work, atol=1e-9)
    assert simloop.run().energy is None
    # The audit changes no physics: the 22 base columns are the same bits.
    base = simloop.run().trajectory
    assert np.array_equal(result.trajectory[:, :22], base, equal_nan=True)


def test_the_audit_separates_stable_from_unstable():
    # Measured over 4 s without the shove: contacts' positive work 0.0354 J at
    # 0.002 s against 0.2991 J at 0.05 s.
    fine = simloop.run(timestep=0.002, steps=2000, perturb=False, audit_energy=True).energy
    coarse = simloop.run(timestep=0.05, steps=80, perturb=False, audit_energy=True).energy
    assert fine["work_constraint_positive"] < expected("energy_audit.fine_positive_contact_work_max")
    assert 0.2 < coarse["work_constraint_positive"]
    assert abs(coarse["unexplained"]) > 5 * abs(fine["unexplained"])


def test_sweep_finds_the_edge_and_the_sinking():
    result = simloop.sweep([0.001, 0.002, 0.004, 0.005, 0.008, 0.02, 0.04, 0.5, 1.0])
    assert result.edge == 0.004
    assert [p.stable for p in result.points] == expected("sweep.stable_at_0_001_to_1")
    assert [p.steps for p in result.points][:3] == [4000, 2000, 1000]
    assert result.points[-2].final_box_z < 0 and result.points[-1].final_box_z < result.points[-2].final_box_z
    # The same sweep from the default range has the edge between 0.003 and 0.005.
    default = simloop.sweep(threads=2)
    assert len(default.points) == 25 and 0.003 < default.edge < 0.005


def test_sweep_commands_agree(tmp_path):
    flags = ["sweep", "--timesteps", "0.002,0.005,0.05", "--out", "o"]
    for name, python in (("py", True), ("cpp", False)):
        (tmp_path / name).mkdir()
        proc = run_command(flags, tmp_path / name, python=python)
        assert proc.returncode == 0, proc.stderr
        assert "largest stable timestep: 0.002 s" in proc.stdout
        assert not (tmp_path / name / "o" / "sweep.png").exists()  # both draw only with --plot
    assert (tmp_path / "py" / "o" / "sweep.csv").read_bytes() == (tmp_path / "cpp" / "o" / "sweep.csv").read_bytes()


def test_both_sweep_commands_plot_when_asked(tmp_path):
    flags = ["sweep", "--timesteps", "0.002,0.05", "--duration", "0.5", "--plot", "--out", "o"]
    env = {"SIMLOOP_PYTHON": sys.executable, "PATH": "/usr/bin:/bin"}  # sim_loop draws through this Python
    for name, cmd in (("py", [sys.executable, "-m", "simloop"]), ("cpp", [str(sim_loop_exe())])):
        (tmp_path / name).mkdir()
        proc = subprocess.run(cmd + flags, cwd=tmp_path / name, capture_output=True, text=True, env=env, timeout=120)
        assert proc.returncode == 0, proc.stderr
        png = tmp_path / name / "o" / "sweep.png"
        assert png.read_bytes()[:4] == b"\x89PNG"
        assert "plot: o/sweep.png" in proc.stdout


def test_the_default_sweep_is_round_and_the_same_in_both_front_ends():
    default = simloop._core.default_sweep_timesteps()
    assert default[0] == 0.0005 and default[-1] == 1.0 and default == sorted(default)
    for t in default:
        assert float(f"{t:.0e}") == t and f"{t:.0e}"[0] in "1234568", t
    assert [p.timestep for p in simloop.sweep().points] == default  # 4 s: every point has 4 steps or more
    assert list(simloop._core.parse_command_line(["sweep"]).sweep_timesteps) == default


def test_plots_are_pictures(tmp_path):
    proc = run_command(["--timestep", "0.05", "--no-perturb", "--no-rerun", "--plot", "--out", "o"], tmp_path)
    assert proc.returncode == 0, proc.stderr
    png = tmp_path / "o" / "trajectory.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000
    # sim_loop --plot hands the drawing to this Python.
    cpp = subprocess.run(
        [str(sim_loop_exe()), "sweep", "--timesteps", "0.002,0.05", "--plot", "--out", "s"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env={"SIMLOOP_PYTHON": sys.executable, "PATH": "/usr/bin:/bin"},
    )
    assert cpp.returncode == 0, cpp.stderr
    assert (tmp_path / "s" / "sweep.png").read_bytes()[:4] == b"\x89PNG"


@pytest.fixture(scope="module")
def baseline_and_break_it(tmp_path_factory):
    root = tmp_path_factory.mktemp("runs")
    for name, kwargs in (
        ("baseline", {"perturb": False}),
        ("shoved", {}),
        ("break-it", {"timestep": 0.05, "perturb": False}),
    ):
        simloop.run(**kwargs).write(root / name)
    return root


def test_trajectory_picture_shows_the_pusher_the_contacts_and_a_fixed_z(baseline_and_break_it):
    from simloop import plots

    root = baseline_and_break_it
    fig = plots.trajectory_figure(root / "shoved" / "trajectory.csv")
    ax_x, ax_y, ax_z, ax_c = fig.axes
    try:
        result = simloop.run()
        lines = {id(line): line for line in ax_x.get_lines()}
        ys = [line.get_ydata() for line in lines.values()]
        assert any(np.array_equal(y, result.column("pusher_x")) for y in ys)  # the pusher is drawn
        assert any(np.array_equal(y, result.column("box_x")) for y in ys)
        assert any(np.array_equal(line.get_ydata(), result.column("ncon")) for line in ax_c.get_lines())
        # z is not autoscaled: a sound run keeps Break It's scale.
        assert ax_z.get_ylim() == plots.Z_RANGE
        # The legend sits above the axes, not on them.
        [legend] = fig.legends
        assert not any(ax.get_legend() for ax in fig.axes)
        assert "shove +7.0 N in y, steps 1000 to 1049" in [t.get_text() for t in legend.get_texts()]
    finally:
        plots._pyplot().close(fig)
    wild = plots.trajectory_figure(root / "break-it" / "trajectory.csv")
    try:
        low, high = wild.axes[2].get_ylim()
        z = simloop.run(timestep=0.05, perturb=False).column("box_z")
        assert low < z.min() and high == plots.Z_RANGE[1]  # widened only where the run leaves it
    finally:
        plots._pyplot().close(wild)


def test_two_runs_on_the_same_axes(baseline_and_break_it, tmp_path):
    root = baseline_and_break_it
    proc = run_command(
        ["plot", "trajectory", "--out", str(root / "baseline"), "--compare", str(root / "break-it")], tmp_path
    )
    assert proc.returncode == 0, proc.stderr
    png = root / "baseline" / "trajectory_vs_break-it.png"
    assert proc.stdout == f"plot: {png}\n" and png.read_bytes()[:4] == b"\x89PNG"
    assert not (root / "baseline" / "trajectory.png").exists()  # the run's own picture is left alone
    from simloop import plots

    fig = plots.trajectory_figure(root / "baseline" / "trajectory.csv", [root / "break-it" / "trajectory.csv"])
    try:
        # Different timesteps (4 s against 100 s): steps on the x axis, both runs drawn.
        assert fig.axes[3].get_xlabel().startswith("step")
        assert len(fig.axes[2].get_lines()) >= 4  # two z tracks and two peak markers
        texts = [t.get_text() for t in fig.legends[0].get_texts()]
        assert "baseline: 2000 steps of 0.002 s, no shove" in texts
        assert "break-it: 2000 steps of 0.05 s, no shove" in texts
    finally:
        plots._pyplot().close(fig)
    same = plots.trajectory_figure(root / "baseline" / "trajectory.csv", [root / "shoved" / "trajectory.csv"])
    try:
        assert same.axes[3].get_xlabel() == "sim time (s)"  # same timestep: time
    finally:
        plots._pyplot().close(same)


@pytest.mark.parametrize(
    "args, message",
    [
        (["plot", "trajectory", "--out", "nowhere"], "--out: nowhere/trajectory.csv: no such file"),
        (["plot", "trajectory", "--compare", "nowhere"], "no such file"),
        (["plot", "trajectory", "--x", "sideways"], "plot: --x must be auto, time or step, got 'sideways'"),
        (["plot", "sweep", "--compare", "x"], "plot: --compare draws trajectories only"),
        (["plot"], "plot needs 'trajectory' or 'sweep' first"),
    ],
)
def test_plot_refuses_bad_arguments(tmp_path, args, message):
    proc = run_command(args, tmp_path)
    assert proc.returncode == 2
    assert message in proc.stderr and len(proc.stderr.splitlines()) == 1


def test_sweep_picture_zooms_on_the_band_and_marks_the_rest(tmp_path):
    from simloop import plots, sweep_plots

    timesteps = [0.001, 0.002, 0.004, 0.005, 0.04, 0.05, 0.5]
    csv = simloop.sweep(timesteps).write(tmp_path)
    fig = sweep_plots.sweep_figure(csv)
    try:
        ax_z = fig.axes[0]
        assert ax_z.get_ylim() == sweep_plots.SWEEP_Z_RANGE  # the 6 mm band fills a quarter of the panel
        points = {p.timestep: p for p in simloop.sweep(timesteps).points}
        labels = [t.get_text() for t in ax_z.texts]
        # The far points are on the edge with their values: Break It's peak at
        # 0.04 s (0.0963 m) and the box under the floor at 0.5 s.
        assert f"{points[0.04].peak_box_z:.3g}" in labels and f"{points[0.5].final_box_z:.3g}" in labels
        # Named by what the sweep ran: Break It's timestep over 4 s is not Break It's 2000 steps.
        assert (
            "the chapter's 0.002 s" in labels and f"Break It's 0.05 s\n{points[0.05].steps} steps, not 2000" in labels
        )
        assert {line.get_xdata()[0] for line in ax_z.get_lines() if len(line.get_xdata()) == 2} >= {0.002, 0.05}
        for ax in fig.axes:  # every legend beside its axes
            legend = ax.get_legend()
            assert legend is None or legend.get_bbox_to_anchor().x0 >= ax.get_window_extent().x1 - 1
    finally:
        plots._pyplot().close(fig)


def test_plot_needs_a_python_with_simloop(tmp_path):
    cpp = subprocess.run(
        [str(sim_loop_exe()), "--smoke", "--plot", "--out", "o"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env={"SIMLOOP_PYTHON": "/nonexistent/python"},
    )
    assert cpp.returncode == 1
    assert "--plot: cannot start /nonexistent/python" in cpp.stderr
    assert (tmp_path / "o" / "metrics.json").exists()  # the run itself was written


@pytest.mark.parametrize(
    "kwargs, error, message",
    [
        ({"timesteps": []}, ValueError, "timesteps must not be empty"),
        ({"timesteps": [0.002, -1]}, ValueError, "timestep must be a positive, finite number of seconds, got -1.0"),
        ({"duration": 0}, ValueError, "duration must be a positive, finite number of seconds, got 0.0"),
        ({"threads": 4097}, ValueError, "threads must be from 1 to 4096, or 0 for one per core, got 4097"),
    ],
)
def test_sweep_refuses_bad_arguments(kwargs, error, message):
    with pytest.raises(error) as caught:
        simloop.sweep(**kwargs)
    assert message in str(caught.value)
