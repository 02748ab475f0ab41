"""A batch reads its files as they are when it starts: a scene's MJCF, every
file it includes, the scenario file and its CSV inputs. Executors' workers,
which keep compiled scenes between batches, give after an edit the table a
local batch gives of the files as they are now, bit for bit; `batch
--resume` refuses, in one line naming the file, parts written while a file
was otherwise; and two batches on one --out do not both run."""

import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
import simloop
from conftest import ROOT, batch

pytest.importorskip("pyarrow")

SCENES = ROOT / "tests" / "scenes"
TBLOCK = SCENES.joinpath("pusht.xml").read_text().split('<body name="tblock"')[1].split("</body>")[0]


def write_scene(folder: Path) -> dict:
    """PushT with its T-block in an included file and push_x from a CSV file: {what: the file that holds it}."""
    scene = (
        SCENES.joinpath("pusht.xml")
        .read_text()
        .replace(f'<body name="tblock"{TBLOCK}</body>', '<include file="tblock.xml"/>')
    )
    assert "tblock.xml" in scene
    (folder / "pusht.xml").write_text(scene)
    (folder / "tblock.xml").write_text(f'<mujoco>\n<body name="tblock"{TBLOCK}</body>\n</mujoco>\n')
    (folder / "push_x.csv").write_text("push_x\n" + "0.8\n" * 50 + "0.6\n")
    toml = SCENES.joinpath("pusht.toml").read_text().replace("value = 0.8", 'csv = "push_x.csv"')
    assert 'csv = "push_x.csv"' in toml
    (folder / "pusht.toml").write_text(toml)
    return {
        "scene": folder / "pusht.xml",
        "include": folder / "tblock.xml",
        "csv": folder / "push_x.csv",
        "scenario": folder / "pusht.toml",
    }


# An edit of each file that changes the runs' numbers.
EDITS = {
    "scene": ('damping="5"', 'damping="3"'),
    "include": ('mass="0.2"', 'mass="0.5"'),
    "csv": ("0.6\n", "-0.4\n"),
    "scenario": ("newtons = [0.5, 1.5]", "newtons = [2.5, 3.5]"),
}


def edit(path: Path, what: str) -> None:
    old, new = EDITS[what]
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new))


@pytest.mark.parametrize("what", ["scene", "include", "csv"])
def test_an_executor_batch_after_an_edit_is_the_local_batch_of_the_edited_files(tmp_path, what):
    files = write_scene(tmp_path)
    scenario = files["scenario"]

    def both():
        local = simloop.run_scenario_batch(str(scenario), seeds=range(4), steps=200, metrics_only=True, threads=2)
        with ThreadPoolExecutor(2) as pool:
            remote = simloop.run_scenario_batch(str(scenario), seeds=range(4), steps=200, executor=pool, chunk_size=2)
        return local, remote

    before, before_remote = both()
    assert before_remote == before
    edit(files[what], what)
    after, after_remote = both()
    assert after != before, "the edit changes no number: the test would prove nothing"
    assert after_remote == after  # not the scene the workers compiled before


def test_a_worker_refuses_a_scene_edited_since_the_batch_started(tmp_path):
    files = write_scene(tmp_path)
    scenario = simloop.Scenario.from_file(files["scenario"])  # read now; its scene is compiled on each worker
    from simloop import distributed

    job = distributed.scenario_job(scenario)
    edit(files["include"], "include")
    with pytest.raises(distributed.InputMismatch, match=r"tblock\.xml is not the file the batch started with"):
        distributed.run_chunk(job, [(0, 0, None, ())])


@pytest.mark.parametrize("what", ["scene", "include", "csv", "scenario"])
def test_resume_refuses_parts_written_before_an_edit_naming_the_file(tmp_path, what):
    from test_batch_resume import interrupted

    files = write_scene(tmp_path)
    args = ["--scenario", "pusht.toml", "--seeds", "0:300", "--steps", "300", "--chunk-size", "10", "--threads", "1"]
    parts = interrupted(args, tmp_path, "cut.parquet", 2)
    before = {p.name: p.read_bytes() for p in parts.iterdir()}
    edit(files[what], what)
    refused = batch([*args, "--out", "cut.parquet", "--resume"], tmp_path)
    assert refused.returncode == 2, refused.stderr
    assert refused.stderr.count("\n") == 1, refused.stderr
    assert refused.stderr.startswith(f"sim-loop: batch: --resume: {files[what]} is not the file it was when "), (
        refused.stderr
    )
    assert not (tmp_path / "cut.parquet").exists()
    assert {p.name: p.read_bytes() for p in parts.iterdir()} == before, "the parts folder changed"


def test_a_second_batch_on_the_same_out_is_refused_and_the_first_finishes_whole(tmp_path):
    args = ["--seeds", "0:300", "--steps", "300", "--chunk-size", "10", "--threads", "1"]
    alone = batch([*args, "--out", "alone.parquet"], tmp_path)
    assert alone.returncode == 0, alone.stderr
    parts = tmp_path / "out" / "b.parquet.parts"
    with subprocess.Popen(
        [sys.executable, "-m", "simloop", "batch", *args, "--out", "out/b.parquet"],
        cwd=tmp_path,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    ) as first:
        deadline = time.monotonic() + 120
        while not any(parts.glob("chunk-*.parquet")):  # it is writing: it holds the folder by then
            assert first.poll() is None and time.monotonic() < deadline, "the first batch ended before it was paused"
            time.sleep(0.02)
        first.send_signal(signal.SIGSTOP)  # paused mid-batch, so the second surely starts while it runs
        try:
            second = batch([*args[:3], "299", *args[4:], "--out", "out/b.parquet"], tmp_path)  # another batch
        finally:
            first.send_signal(signal.SIGCONT)
        _, err = first.communicate(timeout=300)
    assert first.returncode == 0, err
    assert second.returncode == 2, second.stderr
    assert second.stderr.count("\n") == 1, second.stderr
    assert second.stderr.startswith("sim-loop: batch: --out: ") and "another simloop run (pid " in second.stderr, (
        second.stderr
    )
    assert (tmp_path / "out" / "b.parquet").read_bytes() == (tmp_path / "alone.parquet").read_bytes()
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["b.parquet"]
