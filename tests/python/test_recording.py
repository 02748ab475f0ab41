"""The chapter's .rrd recording, opened and checked against the run it
records: its scene drawn from the scene's own geometry, as any scenario's is
(test_scenario_recording.py), with the chapter's shove arrow and plots."""

import numpy as np
import pyarrow as pa
import pytest
import rerun.chunk
import simloop
from conftest import run_command
from simloop import recording
from simloop import recording_views as views
from simloop._rerun_parts import _rotate_into_body, value_axis_range

# The box, the pusher and the shove at the chapter's own paths ("the same entity
# paths every chapter uses").
TEMPORAL = [
    "/world/objects/box",
    "/world/robot/pusher",
    "/world/objects/box/shove",
    "/plots/box_x",
    "/plots/box_y",
    "/plots/box_z",
    "/plots/box_speed",
    "/plots/pusher_x",
    "/plots/ncon",
]
ENERGY = ["/plots/" + name for name in simloop.ENERGY_COLUMN_NAMES]


def load_chunks(path, store=None):
    """{(entity path, static): merged record-batch columns as Python lists}, without row ids."""
    reader = rerun.chunk.RrdReader(str(path))
    merged = {}
    for chunk in reader.stream(store=store):
        batch = chunk.to_record_batch()
        entry = merged.setdefault((chunk.entity_path, chunk.is_static), {})
        for name in batch.schema.names:
            column = batch.column(name)
            if name.endswith("RowId"):  # a fresh time-based id per row, every time
                continue
            if pa.types.is_duration(column.type):  # sim_time: nanoseconds
                column = column.cast(pa.int64())
            if pa.types.is_timestamp(column.type):
                column = column.cast(pa.int64())
            entry.setdefault(name, []).extend(column.to_pylist())
    return merged


def scalars(chunks, entity):
    return np.array([v[0] for v in chunks[(entity, False)]["Scalars:scalars"]])


def recordings(path):
    return [(r.application_id, r.recording_id) for r in rerun.chunk.RrdReader(str(path)).recordings()]


def record_with_command(tmp_path, name, flags):
    out = tmp_path / name
    proc = run_command([*flags, "--out", str(out)], tmp_path)
    assert proc.returncode == 0, proc.stderr
    rrd = out / "sim_loop.rrd"
    assert f"recording: {rrd} -- open it with: " in proc.stdout  # the viewer: test_readme_commands.py
    return rrd


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    rrd = record_with_command(tmp_path_factory.mktemp("rec"), "o", ["--seed", "0"])
    return load_chunks(rrd), simloop.run(seed=0)


def test_entities_timelines_and_every_step(recorded):
    chunks, result = recorded
    assert {entity for entity, static in chunks if not static} == set(TEMPORAL)
    assert {entity for entity, static in chunks if static} == {
        "/world/static/floor",
        "/world/objects/box/box_geom",
        "/world/robot/pusher/pusher_geom",
        "/world/objects/box/camera_frame",
        "/world/objects/box/shove",
        "/plots/box_x",
        "/plots/box_y",
        "/plots/box_z",
        "/plots/box_speed",
        "/plots/pusher_x",
        "/plots/ncon",
        "/__properties",
    }
    times = result.column("time")
    for entity in TEMPORAL:
        columns = chunks[(entity, False)]
        # Every step, from the rest pose at t = 0 to the final state.
        assert columns["step"] == list(range(2001)), entity
        np.testing.assert_allclose(np.array(columns["sim_time"]) / 1e9, times, rtol=0, atol=1e-9)


def test_the_scenes_own_boxes_and_the_floor(recorded):
    chunks, result = recorded
    box = chunks[("/world/objects/box/box_geom", True)]
    pusher = chunks[("/world/robot/pusher/pusher_geom", True)]
    # The chapter's scene's sizes and colours (rgba 0.85 0.3 0.25, 0.25 0.45 0.85), packed 0xRRGGBBAA.
    np.testing.assert_allclose(box["Boxes3D:half_sizes"][0], [[0.05, 0.05, 0.05]])
    np.testing.assert_allclose(pusher["Boxes3D:half_sizes"][0], [[0.04, 0.12, 0.05]])
    assert box["Boxes3D:colors"][0] == [(217 << 24) | (77 << 16) | (64 << 8) | 255]
    assert pusher["Boxes3D:colors"][0] == [(64 << 24) | (115 << 16) | (217 << 8) | 255]
    assert box["Transform3D:translation"][0] == [[0.0, 0.0, 0.0]]  # each geom sits at its body's origin
    floor = chunks[("/world/static/floor", True)]
    assert floor["Transform3D:translation"][0] == [[0.0, 0.0, 0.0]]  # the plane's own frame is the world's
    centre, half = np.array(floor["Boxes3D:centers"][0][0]), np.array(floor["Boxes3D:half_sizes"][0][0])
    assert abs(centre[2] + half[2]) < 1e-6  # its top is the floor, z = 0
    # It is the scene's floor, 4 m x 4 m (geom size 2 2), not the run's: the
    # box slides off it at x = 2 m onto MuJoCo's infinite plane.
    # (rerun stores float32: a few 1e-7 either way)
    np.testing.assert_allclose(centre[:2], [0.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(half[:2], [2.0, 2.0], atol=1e-6)
    assert result.column("box_x").max() > 2.0


def test_the_shove_arrow_has_its_own_colour_and_the_camera_follows_the_box(recorded):
    chunks, _ = recorded
    arrow = chunks[("/world/objects/box/shove", True)]
    assert arrow["Arrows3D:colors"][0] == [(255 << 24) | (190 << 16) | (0 << 8) | 255]  # amber, not the box's red
    assert arrow["Arrows3D:radii"][0] == [pytest.approx(0.008)]
    # The camera follows an invisible frame around the box (rerun frames a
    # tracked entity by its bounds; the 10 cm box alone would fill the view).
    frame = chunks[("/world/objects/box/camera_frame", True)]
    np.testing.assert_allclose(frame["Boxes3D:half_sizes"][0], [[0.6, 0.6, 0.3]])
    assert frame["Boxes3D:colors"][0] == [0]  # fully transparent


def test_box_pose_matches_the_trajectory(recorded):
    chunks, result = recorded
    box = chunks[("/world/objects/box", False)]
    rows = result.trajectory
    names = simloop.COLUMN_NAMES
    translations = np.array([t[0] for t in box["Transform3D:translation"]])
    expected = rows[:, [names.index(c) for c in ("box_x", "box_y", "box_z")]]
    np.testing.assert_allclose(translations, expected, rtol=0, atol=1e-6)  # stored as float32
    quats = np.array([q[0] for q in box["Transform3D:quaternion"]])
    wxyz = rows[:, [names.index(c) for c in ("box_qw", "box_qx", "box_qy", "box_qz")]]
    np.testing.assert_allclose(quats, wxyz[:, [1, 2, 3, 0]], atol=1e-6)  # rerun is x-y-z-w
    pusher = chunks[("/world/robot/pusher", False)]
    translations = np.array([t[0] for t in pusher["Transform3D:translation"]])
    np.testing.assert_allclose(translations[:, 0], rows[:, names.index("pusher_x")], atol=1e-6)
    np.testing.assert_allclose(translations[:, 1:], 0.0 * translations[:, 1:] + [0.0, 0.05], atol=1e-7)
    assert np.ptp(translations[:, 0]) > 4  # it does move
    assert all(q == [[0.0, 0.0, 0.0, 1.0]] for q in pusher["Transform3D:quaternion"])  # a slide never turns it


def test_the_series_are_the_trajectory_exactly(recorded):
    chunks, result = recorded
    for column in ("box_x", "box_y", "box_z", "pusher_x", "ncon"):
        np.testing.assert_array_equal(scalars(chunks, "/plots/" + column), result.column(column), err_msg=column)
    v = np.column_stack([result.column(c) for c in ("box_vx", "box_vy", "box_vz")])
    np.testing.assert_allclose(scalars(chunks, "/plots/box_speed"), np.linalg.norm(v, axis=1), rtol=1e-15)
    # Each series is named for the viewer's legend, the box's in the box's colour.
    assert chunks[("/plots/box_z", True)]["SeriesLines:names"][0] == ["box z (m), height of its centre"]
    assert chunks[("/plots/box_z", True)]["SeriesLines:colors"][0] == [(217 << 24) | (77 << 16) | (64 << 8) | 255]


def test_the_arrow_shows_the_shove_exactly_while_it_acts(recorded):
    chunks, result = recorded
    arrows = chunks[("/world/objects/box/shove", False)]
    vectors = np.array([v[0] for v in arrows["Arrows3D:vectors"]])
    origins = np.array([o[0] for o in arrows["Arrows3D:origins"]])
    steps = np.arange(0, 2001)
    inside = (steps >= result.shove.start_step) & (steps < result.shove.start_step + result.shove.steps)
    lengths = np.linalg.norm(vectors, axis=1)
    assert inside.sum() == 50
    assert np.all(lengths[~inside] == 0.0)
    # In the box's frame (the entity is the box's child), 0.02 x the shove.
    np.testing.assert_allclose(lengths[inside], 0.02 * result.shove.newtons, rtol=1e-6)
    # From 8 cm above the box's centre in the world (3 cm above its top face, in view for either sign), so in
    # the box's frame that offset rotated into it; the arrow's direction is the world's shove.
    quat = np.column_stack([result.column(c) for c in ("box_qw", "box_qx", "box_qy", "box_qz")])
    np.testing.assert_allclose(origins, _rotate_into_body(quat, np.tile([0.0, 0.0, 0.08], (2001, 1))), atol=1e-12)
    assert np.all(np.abs(origins[:, 2] - 0.08) < 1e-3)  # the box stays about flat in the default run
    assert np.all(np.abs(vectors[inside][:, 1]) > 0.9 * lengths[inside])  # sideways, as the shove


def test_a_model_of_the_chapters_layout_is_drawn_as_it_is(tmp_path):
    # The pusher is whichever body actuator 0 drives, whatever its name, with its own shape and home.
    scene = tmp_path / "ram.xml"
    scene.write_text(
        simloop._core.PUSHER_SCENE_XML.replace(
            '<body name="pusher" pos="0 0 0.05">', '<body name="ram" pos="0 0.1 0.05">'
        ).replace('size="0.04 0.12 0.05"', 'size="0.03 0.2 0.05"')
    )
    chunks = load_chunks(record_with_command(tmp_path, "m", ["--smoke", "--model", str(scene)]))
    result = simloop.run(model=scene, smoke=True)
    assert ("/world/robot/pusher", False) not in chunks
    np.testing.assert_allclose(
        chunks[("/world/robot/ram/pusher_geom", True)]["Boxes3D:half_sizes"][0], [[0.03, 0.2, 0.05]]
    )
    ram = np.array([t[0] for t in chunks[("/world/robot/ram", False)]["Transform3D:translation"]])
    np.testing.assert_allclose(ram[:, 0], result.column("pusher_x"), atol=1e-6)
    np.testing.assert_allclose(ram[:, 1:], 0.0 * ram[:, 1:] + [0.1, 0.05], atol=1e-7)


def test_record_writes_an_in_memory_run_as_the_command_does(tmp_path):
    from_command = record_with_command(tmp_path, "c", ["--smoke", "--seed", "3"])
    path = recording.record(simloop.run(smoke=True, seed=3), tmp_path / "r.rrd")
    assert path == tmp_path / "r.rrd" and recordings(path) == recordings(from_command)
    assert load_chunks(path) == load_chunks(from_command)


def test_break_its_peak_is_in_the_file(tmp_path):
    rrd = record_with_command(tmp_path, "b", ["--timestep", "0.05", "--no-perturb"])
    chunks = load_chunks(rrd)
    z = scalars(chunks, "/plots/box_z")
    steps = chunks[("/plots/box_z", False)]["step"]
    trajectory_z = simloop.run(timestep=0.05, perturb=False).column("box_z")
    assert z.max() == trajectory_z.max()
    assert steps[int(np.argmax(z))] == int(np.argmax(trajectory_z))
    # The transform carries it too (as float32).
    box_z = np.array([t[0][2] for t in chunks[("/world/objects/box", False)]["Transform3D:translation"]])
    assert abs(box_z.max() - trajectory_z.max()) < 1e-6


def test_the_energy_audit_is_recorded_when_on(tmp_path):
    rrd = record_with_command(tmp_path, "e", ["--smoke", "--energy-audit"])
    chunks = load_chunks(rrd)
    result = simloop.run(smoke=True, audit_energy=True)
    for entity, column in zip(ENERGY, simloop.ENERGY_COLUMN_NAMES):
        np.testing.assert_array_equal(scalars(chunks, entity), result.column(column), err_msg=entity)
    plain = load_chunks(record_with_command(tmp_path, "p", ["--smoke"]))
    assert not any(entity in ENERGY for entity, _ in plain)


def test_the_recording_id_follows_the_run(tmp_path):
    a = record_with_command(tmp_path, "a", ["--smoke"])
    again = record_with_command(tmp_path, "again", ["--smoke"])
    other_seed = record_with_command(tmp_path, "seed", ["--smoke", "--seed", "1"])
    other_rng = record_with_command(tmp_path, "rng", ["--smoke", "--rng", "numpy"])
    ids = [recordings(p) for p in (a, again, other_seed, other_rng)]
    assert all(len(i) == 1 and i[0][0] == "simloop_ch0_1_sim_loop" for i in ids)
    assert ids[0] == ids[1]  # the same run: the same recording
    assert len({i[0][1] for i in ids[1:]}) == 3  # different runs: different recordings
    # Identical runs hold identical data (the bytes differ: rerun's row and
    # chunk ids are time-based, and the blueprint's store id is random).
    assert load_chunks(a) == load_chunks(again)


def test_recording_id_sees_every_parameter_and_the_model(tmp_path):
    base = simloop.run(steps=20)
    same = views.recording_id(base)
    assert views.recording_id(simloop.run(steps=20)) == same
    for kwargs in (
        {"seed": 1},
        {"timestep": 0.001},
        {"perturb": False},
        {"rng": "numpy"},
        {"record_every": 2},
        {"audit_energy": True},
        {"steps": 21},
    ):
        assert views.recording_id(simloop.run(**{"steps": 20, **kwargs})) != same, kwargs
    scene = tmp_path / "scene.xml"
    scene.write_text(simloop._core.PUSHER_SCENE_XML)
    assert views.recording_id(base, scene) != same  # a file is identified by its bytes
    scene2 = tmp_path / "scene2.xml"
    scene2.write_text(simloop._core.PUSHER_SCENE_XML.replace('damping="4"', 'damping="5"'))
    assert views.recording_id(base, scene2) != views.recording_id(base, scene)


def test_the_recording_id_sees_the_mujoco_build(monkeypatch):
    # The same run on Debian's 2.2.2 and on the PyPI build's 4.0.0 moves
    # otherwise: two recordings, not one merged ("one recording per run").
    config = simloop.run(steps=20).config
    ids = {}
    for version, build in (("MuJoCo 2.2.2", "system"), ("MuJoCo 4.0.0", "pypi")):
        monkeypatch.setattr(simloop._core, "MUJOCO_VERSION", version)
        monkeypatch.setattr(views, "MUJOCO_BUILD", build)
        assert views.config_parameters(config)["mujoco"] == f"{version} ({build})"
        ids[version] = (
            views.config_recording_id(config),
            views.config_recording_id(config),
            views.scenario_recording_id("key"),
            views.scenario_recording_id("key"),
        )
    for same_build in ids.values():  # the same run on one build: one id
        assert same_build[0] == same_build[1] and same_build[2] == same_build[3]
    two_builds = list(ids.values())
    assert two_builds[0][0] != two_builds[1][0]  # the chapter's run
    assert two_builds[0][2] != two_builds[1][2]  # a scenario's


def test_the_blueprint_opens_the_3d_view_beside_the_time_series(tmp_path):
    rrd = record_with_command(tmp_path, "bp", ["--smoke"])
    reader = rerun.chunk.RrdReader(str(rrd))
    [store] = reader.blueprints()
    chunks = load_chunks(rrd, store=store)
    by_entity = {entity: columns for (entity, _), columns in chunks.items()}

    def single(entity, field):
        [value] = [v for name, v in by_entity[entity].items() if name.endswith(":" + field)]
        return value[0]

    root_uuid = single("/viewport", "root_container")[0]
    root = "/container/" + "".join(f"{b:02x}" for b in root_uuid)
    root = next(e for e in by_entity if e.replace("-", "") == root)
    assert single(root, "container_kind")[0] == 2  # Horizontal
    left, right = single(root, "contents")
    assert single("/" + left, "class_identifier") == ["3D"]
    assert single("/" + left, "space_origin") == ["/world"]
    assert single("/" + right, "container_kind")[0] == 3  # Vertical: the time series, stacked
    views = single("/" + right, "contents")
    assert all(single("/" + v, "class_identifier") == ["TimeSeries"] for v in views)
    assert single("/" + views[0] + "/ViewContents", "query") == ["/plots/box_z"]
    assert single("/time_panel", "timeline") == ["sim_time"]  # the timeline the chapter says to scrub


def test_no_rerun_writes_no_recording(tmp_path):
    proc = run_command(["--smoke", "--no-rerun", "--out", "o"], tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert not (tmp_path / "o" / "sim_loop.rrd").exists()
    assert "recording" not in proc.stdout


def test_the_plots_open_on_the_run_legends_off_the_data_and_no_axis_narrower_than_a_centimetre(tmp_path):
    # Break It opened on empty negative time (to -20 s); the legends sat on the traces (the z panel's on its
    # 0.05 m rest line); on MuJoCo 4 a still box's y axis spanned 1e-15 m ("-0.000 000 000 000 002").
    rrd = record_with_command(tmp_path, "bi", ["--timestep", "0.05", "--no-perturb"])
    [store] = rerun.chunk.RrdReader(str(rrd)).blueprints()
    fields: dict = {}
    for (entity, _), columns in load_chunks(rrd, store=store).items():
        for name, value in columns.items():
            if name in ("TimeAxis:view_range", "PlotLegend:visible", "PlotLegend:corner"):
                fields.setdefault(name.split(":")[-1], []).append((entity.split("/")[2], value[0][0]))
    views_with_plots = {view for view, _ in fields["view_range"]}
    assert len(views_with_plots) == 5
    assert all(
        r == {"start": 0, "end": 100 * 10**9 - 1} or r == {"start": 0, "end": 100 * 10**9}
        for _, r in fields["view_range"]
    ), fields["view_range"]  # 2000 steps of 0.05 s: 0 to 100 s
    legends = dict(fields["visible"])
    assert sorted(legends.values()) == [False, False, False, False, True]  # only the x panel has two series
    assert all(corner == 1 for _, corner in fields["corner"])  # the top left
    assert value_axis_range((-1e-15, 2e-15)) == pytest.approx((-0.005 + 5e-16, 0.005 + 5e-16))
    assert value_axis_range((0.0, 0.3)) is None  # wide enough: rerun fits the data
    assert value_axis_range(None) is None


def test_the_chapters_view_refuses_rows_it_does_not_draw_and_writes_nothing(tmp_path):
    # The chapter's view draws the chapter's columns exactly: rows of other
    # columns (the energy audit's, unasked) are an error, not a wrong drawing.
    result = simloop.run(smoke=True, audit_energy=True)
    model = simloop.load_model(None)
    drawing = recording.Recording(
        model, tmp_path / "r.rrd", views.chapter_view(simloop.run(smoke=True).config, None, model)
    )
    try:
        with pytest.raises(ValueError, match="the recording draws the columns"):
            drawing.columns(result.column_names)
    finally:
        drawing.close()
    assert list(tmp_path.iterdir()) == []
