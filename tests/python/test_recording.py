"""The .rrd recording, opened and checked against the run it records."""

import numpy as np
import pyarrow as pa
import pytest
import rerun.chunk

import simloop
from conftest import run_command


def load_chunks(path):
    """{(entity path, static): merged record-batch columns as numpy}."""
    reader = rerun.chunk.RrdReader(str(path))
    assert [r.application_id for r in reader.recordings()] == ["simloop_ch0_1_sim_loop"]
    merged = {}
    for chunk in reader.stream():
        batch = chunk.to_record_batch()
        entry = merged.setdefault((chunk.entity_path, chunk.is_static), {})
        for name in batch.schema.names:
            column = batch.column(name)
            if pa.types.is_duration(column.type):  # sim_time: nanoseconds
                column = column.cast(pa.int64())
            entry.setdefault(name, []).extend(column.to_pylist())
    return merged


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    out = tmp_path_factory.mktemp("rec")
    proc = run_command(["--seed", "0", "--out", str(out)], out)
    assert proc.returncode == 0, proc.stderr
    rrd = out / "sim_loop.rrd"
    assert f"recording: {rrd} -- open it with: " in proc.stdout  # the viewer: test_readme_commands.py
    return load_chunks(rrd), simloop.run(seed=0)


def test_entities_timeline_and_frame_count(recorded):
    chunks, result = recorded
    assert set(chunks) == {("/world/objects/box", False), ("/world/robot/pusher", False),
                           ("/world/objects/box/shove", False), ("/world/objects/box", True),
                           ("/world/robot/pusher", True)}
    for entity in ("/world/objects/box", "/world/robot/pusher", "/world/objects/box/shove"):
        times = chunks[(entity, False)]["sim_time"]
        assert len(times) == 2000 // 5  # every 5th step
        assert times == sorted(times)
    # sim_time is a duration: step k sits at k * timestep seconds.
    ns = np.array(chunks[("/world/objects/box", False)]["sim_time"], dtype=np.int64)
    expected = result.column("time")[::5][:400]
    np.testing.assert_allclose(ns / 1e9, expected, atol=1e-9)


def test_static_boxes(recorded):
    chunks, _ = recorded
    box = chunks[("/world/objects/box", True)]
    pusher = chunks[("/world/robot/pusher", True)]
    np.testing.assert_allclose(box["Boxes3D:half_sizes"][0], [[0.05, 0.05, 0.05]])
    np.testing.assert_allclose(pusher["Boxes3D:half_sizes"][0], [[0.04, 0.12, 0.05]])
    # Colours are packed 0xRRGGBBAA.
    assert box["Boxes3D:colors"][0] == [(217 << 24) | (76 << 16) | (64 << 8) | 255]
    assert pusher["Boxes3D:colors"][0] == [(64 << 24) | (115 << 16) | (217 << 8) | 255]


def test_box_pose_matches_the_trajectory(recorded):
    chunks, result = recorded
    box = chunks[("/world/objects/box", False)]
    rows = result.trajectory[:-1][::5]  # entering steps 0, 5, ..., 1995
    names = simloop.COLUMN_NAMES
    translations = np.array([t[0] for t in box["Transform3D:translation"]])
    expected = rows[:, [names.index(c) for c in ("box_x", "box_y", "box_z")]]
    np.testing.assert_allclose(translations, expected, rtol=0, atol=1e-6)  # stored as float32
    quats = np.array([q[0] for q in box["Transform3D:quaternion"]])
    wxyz = rows[:, [names.index(c) for c in ("box_qw", "box_qx", "box_qy", "box_qz")]]
    np.testing.assert_allclose(quats, wxyz[:, [1, 2, 3, 0]], atol=1e-6)  # rerun is x-y-z-w
    pusher = np.array([t[0] for t in chunks[("/world/robot/pusher", False)]["Transform3D:translation"]])
    np.testing.assert_allclose(pusher[:, 0], rows[:, names.index("pusher_x")], atol=1e-6)
    np.testing.assert_allclose(pusher[:, 1:], 0.0 * pusher[:, 1:] + [0.0, 0.05], atol=1e-7)


def test_the_arrow_shows_the_shove_exactly_while_it_acts(recorded):
    chunks, result = recorded
    arrows = chunks[("/world/objects/box/shove", False)]
    vectors = np.array([v[0] for v in arrows["Arrows3D:vectors"]])
    origins = np.array([o[0] for o in arrows["Arrows3D:origins"]])
    steps = np.arange(0, 2000, 5)
    inside = (steps >= result.shove.start_step) & (steps < result.shove.start_step + result.shove.steps)
    lengths = np.linalg.norm(vectors, axis=1)
    assert inside.sum() == 10
    assert np.all(lengths[~inside] == 0.0)
    # In the box's frame (the entity is the box's child), 0.02 x the shove.
    np.testing.assert_allclose(lengths[inside], 0.02 * result.shove.newtons, rtol=1e-6)
    assert np.all(origins == 0.0)


def test_no_rerun_writes_no_recording(tmp_path):
    proc = run_command(["--smoke", "--no-rerun", "--out", "o"], tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert not (tmp_path / "o" / "sim_loop.rrd").exists()
    assert "recording" not in proc.stdout
