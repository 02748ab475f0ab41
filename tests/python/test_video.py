"""python -m simloop --video FILE: the run's pictures, 25 a simulated second,
as an animated PNG (or an MP4 with ffmpeg), the same bytes every run, put in
place with the run's outputs or not at all; sim_loop refuses it."""

import importlib.util
import os
import shutil
import struct
import sys
import types
import zlib

import numpy as np
import pytest
from conftest import ROOT, run_command

# Every check draws; a machine without EGL says so in the run's one line instead.


def apng_frames(path):
    """(frame count from acTL, [delay of each frame in s], first frame as (h, w, 3) uint8) of an APNG we wrote."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    at, frames, delays, width, height, first = 8, None, [], 0, 0, b""
    while at < len(data):
        size, kind = struct.unpack(">I4s", data[at : at + 8])
        body = data[at + 8 : at + 8 + size]
        assert struct.unpack(">I", data[at + 8 + size : at + 12 + size])[0] == zlib.crc32(kind + body) & 0xFFFFFFFF
        if kind == b"IHDR":
            width, height = struct.unpack(">II", body[:8])
        elif kind == b"acTL":
            frames = struct.unpack(">I", body[:4])[0]
        elif kind == b"fcTL":
            numerator, denominator = struct.unpack(">HH", body[20:24])
            delays.append(numerator / denominator)
        elif kind == b"IDAT":
            first += body
        at += 12 + size
    rows = np.frombuffer(zlib.decompress(first), np.uint8).reshape(height, 1 + 3 * width)
    assert (rows[:, 0] == 1).all()  # each row filtered "Sub"
    picture = np.cumsum(rows[:, 1:].reshape(height, width, 3), axis=1, dtype=np.uint8)  # undo it (mod 256)
    return frames, delays, picture


def test_the_chapters_video_is_an_animated_png_of_every_25th_of_a_second(tmp_path):
    run = run_command(["--seed", "0", "--no-rerun", "--video", "run.png", "--out", "out"], tmp_path)
    assert run.returncode == 0, run.stderr
    assert "video: run.png\n" in run.stdout
    frames, delays, first = apng_frames(tmp_path / "run.png")
    assert frames == len(delays) == 101  # 4 s of simulated time, a frame each 0.04 s, the first at t = 0
    assert delays == [0.04] * 101
    r, g, b = first[240, 320].astype(int)  # the chapter's video looks at the box: red in the middle
    assert r > 2 * g and r > 2 * b
    again = run_command(["--seed", "0", "--no-rerun", "--video", "again.png", "--out", "out2"], tmp_path)
    assert again.returncode == 0, again.stderr
    assert (tmp_path / "again.png").read_bytes() == (tmp_path / "run.png").read_bytes()  # the same bytes
    assert (tmp_path / "out2" / "metrics.json").read_bytes() == (tmp_path / "out" / "metrics.json").read_bytes()


def test_break_its_frames_are_its_rows(tmp_path):
    run = run_command(
        ["--timestep", "0.05", "--no-perturb", "--steps", "40", "--no-rerun", "--video", "b.png", "--out", "out"],
        tmp_path,
    )
    assert run.returncode == 0, run.stderr
    frames, delays, _ = apng_frames(tmp_path / "b.png")
    assert frames == 41 and set(delays) == {0.05}  # rows sparser than 1/25 s: each one a frame, played in real time


def test_a_scenarios_video_draws_its_qpos_with_the_recording_beside(tmp_path):
    run = run_command(
        ["--scenario", str(ROOT / "tests/scenes/pusht.toml"), "--steps", "200", "--video", "pusht.png", "--out", "out"],
        tmp_path,
    )
    assert run.returncode == 0, run.stderr
    frames, delays, first = apng_frames(tmp_path / "pusht.png")
    times = np.loadtxt(tmp_path / "out" / "trajectory.csv", delimiter=",", skiprows=1, usecols=1)
    assert frames == int(times[-1] / 0.04 + 1e-9) + 1 and set(delays) == {0.04}
    assert (tmp_path / "out" / "sim_loop.rrd").stat().st_size > 0  # the recording still made
    assert first.std() > 10  # a picture, not a blank


def without_imageio_ffmpeg(tmp_path, monkeypatch):
    """The command's Python, in a child, finds no imageio_ffmpeg (a package of that name that fails to import)."""
    hidden = tmp_path / "hidden" / "imageio_ffmpeg"
    hidden.mkdir(parents=True)
    (hidden / "__init__.py").write_text("raise ImportError('hidden by the test')\n")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(hidden.parent), os.environ.get("PYTHONPATH")])))


def test_without_ffmpeg_an_mp4_becomes_an_animated_png_and_says_how_to_get_it(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", "/nonexistent")
    without_imageio_ffmpeg(tmp_path, monkeypatch)
    run = run_command(["--smoke", "--no-rerun", "--video", "clip.mp4", "--out", "out"], tmp_path)
    assert run.returncode == 0, run.stderr
    assert (
        "video: clip.png (an animated PNG: ffmpeg, which .mp4 needs, is neither installed with Python "
        "(pip install 'simloop[video]') nor on PATH (apt install ffmpeg))\n"
    ) in run.stdout
    assert not (tmp_path / "clip.mp4").exists()
    assert apng_frames(tmp_path / "clip.png")[0] == 16  # 300 steps of 2 ms: 0.6 s, a frame each 0.04 s


@pytest.mark.parametrize(
    "asked, note", [("clip.gif", ".gif is not a format"), ("clip", "a name without a suffix is not a format")]
)
def test_a_video_asked_in_another_format_is_an_animated_png_and_says_so(asked, note, tmp_path):
    run = run_command(["--smoke", "--steps", "50", "--no-rerun", "--video", asked, "--out", "out"], tmp_path)
    assert run.returncode == 0, run.stderr
    assert f"video: clip.png (an animated PNG: {note} --video writes; FILE.mp4 is an MP4, with ffmpeg)\n" in run.stdout
    assert apng_frames(tmp_path / "clip.png")[0] > 1


def test_ffmpeg_is_imageio_ffmpegs_when_installed_else_the_one_on_path(tmp_path, monkeypatch):
    from simloop import video

    bundled = tmp_path / "bundled-ffmpeg"
    fake = types.ModuleType("imageio_ffmpeg")
    fake.get_ffmpeg_exe = lambda: str(bundled)
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", fake)
    assert video.find_ffmpeg() == str(bundled)
    on_path = tmp_path / "bin" / "ffmpeg"
    on_path.parent.mkdir()
    on_path.write_text("#!/bin/sh\n")
    on_path.chmod(0o755)
    monkeypatch.setenv("PATH", str(on_path.parent))

    def no_binary():
        raise RuntimeError("No ffmpeg exe could be found")

    fake.get_ffmpeg_exe = no_binary  # installed, but without a binary for this machine: PATH's
    assert video.find_ffmpeg() == str(on_path)
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)  # absent: import fails
    assert video.find_ffmpeg() == str(on_path)
    monkeypatch.setenv("PATH", "/nonexistent")
    assert video.find_ffmpeg() is None


@pytest.mark.skipif(importlib.util.find_spec("imageio_ffmpeg") is None, reason="imageio-ffmpeg is not installed")
def test_with_imageio_ffmpeg_an_mp4_is_written_without_ffmpeg_on_path(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", "/nonexistent")
    run = run_command(["--smoke", "--no-rerun", "--video", "clip.mp4", "--out", "out"], tmp_path)
    assert run.returncode == 0, run.stderr
    assert "video: clip.mp4\n" in run.stdout
    data = (tmp_path / "clip.mp4").read_bytes()
    assert data[4:8] == b"ftyp" and b"moof" in data  # a fragmented MP4: written front to back into its pipe


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg is not on PATH")
def test_with_ffmpeg_on_path_an_mp4_is_written(tmp_path, monkeypatch):
    without_imageio_ffmpeg(tmp_path, monkeypatch)
    run = run_command(["--smoke", "--no-rerun", "--video", "clip.mp4", "--out", "out"], tmp_path)
    assert run.returncode == 0, run.stderr
    assert "video: clip.mp4\n" in run.stdout
    data = (tmp_path / "clip.mp4").read_bytes()
    assert data[4:8] == b"ftyp" and b"moof" in data  # a fragmented MP4: written front to back into its pipe


def test_a_video_that_cannot_be_made_leaves_nothing(tmp_path):
    run = run_command(["--smoke", "--no-rerun", "--video", "missing/dir/clip.png", "--out", "out"], tmp_path)
    assert run.returncode == 1
    assert len(run.stderr.splitlines()) == 1 and "missing/dir" in run.stderr
    assert not (tmp_path / "out" / "metrics.json").exists()
    assert not (tmp_path / "missing").exists()
    refused = run_command(["--smoke", "--video", "clip.png", "--out", "out"], tmp_path, python=False)
    assert refused.returncode == 2
    assert refused.stderr == (
        "sim_loop: --video: sim_loop draws no pictures; python -m simloop --video clip.png does (nothing was written)\n"
    )
    assert not (tmp_path / "clip.png").exists() and not (tmp_path / "out" / "metrics.json").exists()
    assert [p for p in os.listdir(tmp_path) if p.startswith(".")] == []  # no temporary file left


@pytest.mark.parametrize(
    "video, says",
    [
        ("out/trajectory.png", "is also the run's --plot's trajectory.png"),
        ("out/metrics.json", "is also the run's metrics.json"),
        ("out/trajectory.gif", "is also the run's --plot's trajectory.png"),  # an APNG at out/trajectory.png
        ("/dev/null", "is a device, a pipe or a socket"),
        ("somewhere/", "must name a file, not a folder"),
        ("folder", "is a folder; name a file in it"),
    ],
)
def test_a_video_never_shares_a_path_with_another_output_nor_writes_a_device_or_a_folder(tmp_path, video, says):
    (tmp_path / "folder").mkdir()
    done = run_command(["--steps", "20", "--no-rerun", "--plot", "--video", video, "--out", "out"], tmp_path)
    assert done.returncode == 2, done.stdout + done.stderr
    assert says in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert not (tmp_path / "out").exists() and not (tmp_path / "somewhere.png").exists()
    assert not os.path.exists("/dev/null.png")


def test_a_timestep_of_a_day_draws_a_video_whose_frames_apng_can_hold(tmp_path):
    done = run_command(
        ["--steps", "3", "--timestep", "86400", "--no-rerun", "--no-perturb", "--video", "v.png", "--out", "out"],
        tmp_path,
    )
    if "cannot render" in done.stderr:
        pytest.skip(done.stderr.strip())
    assert done.returncode == 0, done.stderr[-3000:]
    frames, delays, _ = apng_frames(tmp_path / "v.png")
    assert frames == len(delays) >= 1  # (rows the blow-up left without a finite state are not drawn)
    assert delays == [65535.0] * frames  # a day between frames, held as long as APNG can
