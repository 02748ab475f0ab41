"""The edges an adversarial user found (issue 8), from Python: huge counts,
wrong types on the compiled classes' methods, paths that are not UTF-8, and
running out of memory. Whatever could crash runs in a subprocess."""

import os
import subprocess
import sys

import pytest
import simloop
from conftest import run_python, sim_loop_exe

I64_MAX = 2**63 - 1


# The three repros: a segfault, a double free, a segfault at GC.
@pytest.mark.parametrize(
    "call, where",
    [
        ("simloop.run(steps=2, record_every=2**63-1)", ""),
        ("simloop.run(steps=10, record_every=2**63-1)", ""),
        ("simloop.run_batch(seeds=[0], steps=5, record_every=2**63-1)", "run 0: "),
    ],
)
def test_record_every_past_the_range_is_refused_not_a_crash(call, where):
    proc = run_python(f"""
        import gc
        import simloop
        try:
            {call}
        except ValueError as e:
            print(e)
        gc.collect()
    """)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr[-2000:]}"
    assert proc.stdout == f"{where}record_every must be at most {2**62 - 1}, got {I64_MAX}\n"


def test_python_takes_the_commands_ranges():
    assert simloop.MAX_STEPS == simloop.MAX_RECORD_EVERY == 2**62 - 1
    # The largest record_every runs: the first and the final state.
    result = simloop.run(steps=10, record_every=simloop.MAX_RECORD_EVERY)
    assert result.rows == 2 and list(result.column("step")) == [0.0, 10.0]
    assert simloop.run_batch(seeds=[0], steps=5, record_every=simloop.MAX_RECORD_EVERY).results[0].rows == 2
    for kwargs in ({"steps": 2**62}, {"record_every": 2**62}, {"steps": I64_MAX}):
        with pytest.raises(ValueError, match=r"must be at most 4611686018427387903, got "):
            simloop.run(**kwargs)
    with pytest.raises(ValueError, match="n must be at most"):
        simloop.Sim().step(2**62)
    # The command draws the line at the same place.
    for flag in ("--steps", "--record-every"):
        over = subprocess.run(
            [str(sim_loop_exe()), flag, str(2**62), "--out", "unused"], capture_output=True, text=True
        )
        assert over.returncode == 2 and f"from 1 to {simloop.MAX_STEPS}," in over.stderr


# Wrong types given to the compiled classes' methods: one line naming the
# argument, not pybind11's four-line "incompatible function arguments".
@pytest.fixture(scope="module")
def results():
    return simloop.run(steps=10), simloop.sweep(timesteps=[0.25], duration=1.0, threads=1)


WRONG_TYPES = [
    (
        lambda r, s: simloop.Model.from_file(3),
        TypeError,
        "path must be a path (str, bytes or os.PathLike), got 3 (int)",
    ),
    (
        lambda r, s: simloop.Model.from_file(None),
        TypeError,
        "path must be a path (str, bytes or os.PathLike), got None",
    ),
    (lambda r, s: simloop.Model.from_file(""), ValueError, "path must name an MJCF file, got ''"),
    (lambda r, s: simloop.Model.from_file("a\0b"), ValueError, "path must not contain a NUL character, got 'a\\x00b'"),
    (lambda r, s: simloop.Model.from_xml_string(None), TypeError, "xml must be a str or bytes, got None (NoneType)"),
    (lambda r, s: simloop.Model.from_xml_string("<mujoco/>", 5), TypeError, "source must be a str or bytes, got 5"),
    (lambda r, s: simloop.Model.from_xml_string("\udcfe"), ValueError, "xml must be text that UTF-8 can encode"),
    (
        lambda r, s: simloop.Model.pusher_scene().with_timestep("0.1"),
        TypeError,
        "timestep must be a number, got '0.1' (str)",
    ),
    (
        lambda r, s: simloop.Model.pusher_scene().with_timestep(0),
        ValueError,
        "timestep must be a positive, finite number of seconds, got 0.0",
    ),
    (lambda r, s: r.column(3), TypeError, "name must be a str (a column name), got 3 (int)"),
    (lambda r, s: r.column(b"box_z"), TypeError, "name must be a str (a column name), got b'box_z' (bytes)"),
    (lambda r, s: r.column("\udcfe"), KeyError, "no trajectory column named '\\udcfe'"),
    (lambda r, s: r.column("box_zz"), KeyError, "no trajectory column named 'box_zz' (did you mean 'box_z'?); see"),
    (lambda r, s: r.write(3.5), TypeError, "out must be a path (str, bytes or os.PathLike), got 3.5 (float)"),
    (lambda r, s: r.write(["out"]), TypeError, "out must be a path (str, bytes or os.PathLike), got ['out'] (list)"),
    (lambda r, s: r.write(""), ValueError, "out must name a directory, got ''"),
    (lambda r, s: s.write(None), TypeError, "out must be a path (str, bytes or os.PathLike), got None"),
    (lambda r, s: r.summary(1), TypeError, "RunResult.summary() takes 1 positional argument but 2 were given"),
    (lambda r, s: s.csv(1), TypeError, "SweepResult.csv() takes 1 positional argument but 2 were given"),
    (
        lambda r, s: simloop.run(seed=10**5000),
        ValueError,
        "seed must be an integer from 0 to 18446744073709551615, got an int of 16610 bits",
    ),
    (lambda r, s: simloop.run(timestep=2**1024), ValueError, "timestep must be a number a float can hold"),
    (
        lambda r, s: simloop.Sim().apply_force(__import__("numpy").zeros((3, 1))),
        TypeError,
        "force[0] must be a number, got array([0.]) (ndarray)",
    ),
    (lambda r, s: simloop.run(progress=3), TypeError, "progress must be None or a callable"),
]


@pytest.mark.parametrize("case", range(len(WRONG_TYPES)))
def test_wrong_arguments_get_one_line_naming_them(results, case, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    call, error, message = WRONG_TYPES[case]
    with pytest.raises(error) as caught:
        call(*results)
    text = str(caught.value.args[0])  # a KeyError's str() is the repr of its message
    assert message in text
    assert "\n" not in text and "incompatible function arguments" not in text
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_a_directory_given_as_a_model_is_one_line(tmp_path):
    with pytest.raises((OSError, simloop.MujocoError)) as caught:
        simloop.Model.from_file(tmp_path)
    assert str(tmp_path) in str(caught.value) and "\n" not in str(caught.value)


def test_paths_may_be_bytes_or_path_like(tmp_path):
    scene = tmp_path / "scene.xml"
    scene.write_text(simloop._core.PUSHER_SCENE_XML)
    for path in (scene, str(scene), os.fsencode(scene)):
        assert simloop.Model.from_file(path).nq == simloop.Model.pusher_scene().nq
        assert simloop.run(steps=5, model=path).rows == 6
    metrics, trajectory = simloop.run(steps=5).write(os.fsencode(tmp_path / "out"))
    assert metrics == tmp_path / "out" / "metrics.json" and trajectory.exists()


# `python -m simloop --out $'bad\xfe'`: sim_loop accepts the path; so does Python.
@pytest.mark.parametrize("io_encoding", [None, "utf-8:strict"], ids=["default-io", "strict-io"])
def test_the_python_command_takes_paths_that_are_not_utf8(tmp_path, io_encoding):
    env = dict(os.environ)
    if io_encoding:
        env["PYTHONIOENCODING"] = io_encoding
    (tmp_path / os.fsdecode(b"scene\xfe.xml")).write_text(simloop._core.PUSHER_SCENE_XML)
    args = [b"--smoke", b"--no-rerun", b"--model", b"scene\xfe.xml", b"--out", b"bad\xfe"]
    python = subprocess.run(
        [sys.executable.encode(), b"-m", b"simloop", *args], cwd=tmp_path, capture_output=True, env=env, timeout=120
    )
    assert python.returncode == 0, python.stderr
    assert python.stderr == b""
    assert b"metrics: bad\xfe/metrics.json\n" in python.stdout
    written = tmp_path / os.fsdecode(b"bad\xfe")
    # The same bytes sim_loop writes for the same flags.
    cpp = subprocess.run(
        [os.fsencode(sim_loop_exe()), *args[:-1], b"cpp\xfe"], cwd=tmp_path, capture_output=True, timeout=120
    )
    assert cpp.returncode == 0, cpp.stderr
    theirs = tmp_path / os.fsdecode(b"cpp\xfe")
    for name in ("metrics.json", "trajectory.csv"):
        assert (written / name).read_bytes() == (theirs / name).read_bytes()


def test_a_bad_value_that_is_not_utf8_is_refused_in_one_line(tmp_path):
    proc = subprocess.run(
        [sys.executable.encode(), b"-m", b"simloop", b"--timestep", b"\xfe"],
        cwd=tmp_path,
        capture_output=True,
        timeout=120,
    )
    assert proc.returncode == 2
    assert proc.stderr.count(b"\n") == 1 and b"--timestep must be a positive, finite number" in proc.stderr


def test_running_out_of_memory_is_a_memory_error_naming_the_run():
    # Under a 1.5 GiB address-space limit a 15-million-step trajectory (2.6
    # GB) cannot be held: one clear exception, and the interpreter goes on.
    proc = run_python("""
        import resource
        import simloop
        simloop.run(steps=10)
        with open("/proc/self/status") as status:
            vm = next(int(line.split()[1]) for line in status if line.startswith("VmSize:")) * 1024
        resource.setrlimit(resource.RLIMIT_AS, (vm + 1536 * 2**20, resource.RLIM_INFINITY))
        try:
            simloop.run(steps=15_000_000)
        except (MemoryError, ValueError) as e:
            print(type(e).__name__, e)
        print(simloop.run(steps=10).rows)
    """)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr[-2000:]}"
    first, second = proc.stdout.splitlines()
    assert first.split()[0] in ("MemoryError", "ValueError")
    assert "steps=15000000" in first or "15000000 steps" in first or "steps 15000000" in first, first
    assert second == "11"
