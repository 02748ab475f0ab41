"""Inputs an adversary writes: each ends in one line naming the input, a non-zero exit or an exception, and
nothing written or removed that the user had (issue 38's cases, on every entry point they reach)."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import time

import pytest
from conftest import run_command, run_python, sim_loop_exe

# A table header of 50,000 dotted keys: toml++ recursed once per key and overflowed the stack (exit 139).
DEEP_HEADER = "[" + ".".join(["a"] * 50000) + "]\nb = 1\n"
DEEP_QUOTED_KEY = "x = {" + ".".join(['"a"'] * 50000) + " = 1}\n"


def one_error_line(stderr: str) -> str:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr[-2000:]
    return lines[0]


@pytest.mark.parametrize("text", [DEEP_HEADER, DEEP_QUOTED_KEY], ids=["header", "inline-table"])
@pytest.mark.parametrize("python", [False, True], ids=["sim_loop", "python"])
def test_deep_dotted_keys_are_refused_by_the_commands(tmp_path, text, python):
    (tmp_path / "dd.toml").write_text(text)
    done = run_command(["--scenario", "dd.toml", "--out", "out"], tmp_path, python=python)
    assert done.returncode == 2, done.stderr[-2000:]
    assert "dd.toml:1:" in one_error_line(done.stderr)
    assert "more than 64 dotted parts" in done.stderr
    assert not (tmp_path / "out").exists()


def test_deep_dotted_keys_are_refused_by_the_api_and_the_batch_command(tmp_path):
    (tmp_path / "dd.toml").write_text(DEEP_HEADER)
    done = run_python(f"""
        import simloop
        try:
            simloop.Scenario.from_file({str(tmp_path / "dd.toml")!r})
        except ValueError as e:
            print("refused:", e)
    """)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "refused:" in done.stdout and "more than 64 dotted parts" in done.stdout
    batch = run_command(["batch", "--scenario", "dd.toml", "--seeds", "0:2", "--out", "b.parquet"], tmp_path)
    assert batch.returncode != 0 and batch.returncode != -11, batch.stderr[-2000:]
    assert "more than 64 dotted parts" in one_error_line(batch.stderr)


def test_keys_up_to_the_limit_still_parse_to_the_scenarios_own_error(tmp_path):
    (tmp_path / "d64.toml").write_text("[" + ".".join(["a"] * 64) + "]\nb = 1\n")
    done = run_command(["--scenario", "d64.toml"], tmp_path, python=False)
    assert done.returncode == 2
    assert "dotted parts" not in done.stderr and "d64.toml" in one_error_line(done.stderr)


@pytest.mark.parametrize("python", [False, True], ids=["sim_loop", "python"])
def test_a_scenario_file_is_read_from_a_file_of_at_most_64_mib(tmp_path, python):
    # /dev/zero grew ~0.5 GB/s until killed; a FIFO without a writer blocked the open.
    os.mkfifo(tmp_path / "fifo.toml")
    for path, says in [
        ("/dev/zero", "/dev/zero: is a device, a pipe or a socket, not a scenario file"),
        ("fifo.toml", "fifo.toml: is a device, a pipe or a socket, not a scenario file"),
    ]:
        done = run_command(["--scenario", path, "--out", "out"], tmp_path, python=python)
        assert done.returncode == 2 and one_error_line(done.stderr).endswith(
            says + " (simloop reads its inputs from files)"
        ), done.stderr
    with open(tmp_path / "huge.toml", "wb") as f:
        f.truncate((64 << 20) + 1)  # sparse: no disk, one byte past the limit
    done = run_command(["--scenario", "huge.toml", "--out", "out"], tmp_path, python=python)
    assert done.returncode == 2
    assert one_error_line(done.stderr).endswith("huge.toml: more than 64 MiB, the most a scenario file may hold")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "csv, says",
    [
        ("/dev/zero", "control[0].csv: /dev/zero: is a device, a pipe or a socket, not a CSV file"),
        ("fifo.csv", "fifo.csv: is a device, a pipe or a socket, not a CSV file"),
        ("long.csv", "control[0].csv: long.csv:1: a line longer than 1 MiB"),
    ],
)
def test_a_csv_schedule_is_a_file_read_a_bounded_line_at_a_time(tmp_path, csv, says):
    os.mkfifo(tmp_path / "fifo.csv")
    (tmp_path / "long.csv").write_text("u" * (2 << 20) + "\n0.5\n")
    (tmp_path / "z.toml").write_text(f'steps = 10\n[[control]]\nactuator = "push_motor"\ncsv = "{csv}"\n')
    done = run_command(["--scenario", "z.toml", "--out", "out"], tmp_path, python=False)
    assert done.returncode == 2
    assert says in one_error_line(done.stderr)


def test_a_scene_is_read_from_a_file(tmp_path):
    os.mkfifo(tmp_path / "fifo.xml")
    for path in ("/dev/zero", "fifo.xml"):
        done = run_command(["--model", path, "--out", "out"], tmp_path, python=False)
        assert done.returncode == 2 and "is a device, a pipe or a socket, not an MJCF file" in done.stderr


def test_a_huge_csv_cell_is_quoted_as_a_short_excerpt_and_control_characters_are_escaped(tmp_path):
    (tmp_path / "u.csv").write_text("u\n0.5\n\x1b]0;owned\x07" + "9" * 500_000 + "\n")
    (tmp_path / "s.toml").write_text('steps = 10\n[[control]]\nactuator = "push_motor"\ncsv = "u.csv"\n')
    done = run_command(["--scenario", "s.toml", "--out", "out"], tmp_path, python=False)
    assert done.returncode == 2
    line = one_error_line(done.stderr)
    assert len(line) < 400, line
    assert "u.csv:3: expected a finite number, got '\\x1b]0;owned\\x07999" in line
    assert "(40 of its 500010 bytes)" in line
    assert "\x1b" not in done.stderr and "\x07" not in done.stderr


@pytest.mark.parametrize("python", [False, True], ids=["sim_loop", "python"])
def test_control_characters_in_a_flag_never_reach_the_terminal(tmp_path, python):
    done = run_command(["--model", "\x1b]0;owned\x07.xml"], tmp_path, python=python)
    assert done.returncode != 0
    assert "\x1b" not in done.stderr and "\x07" not in done.stderr
    assert "\\x1b]0;owned\\x07.xml" in one_error_line(done.stderr)


def test_a_path_with_a_nul_byte_is_refused_not_cut_at_the_nul(tmp_path):
    (tmp_path / "s.toml").write_text('steps = 10\n[[control]]\nactuator = "push_motor"\ncsv = "u.csv\\u0000.txt"\n')
    (tmp_path / "u.csv").write_text("u\n0.5\n")
    done = run_command(["--scenario", "s.toml", "--out", "out"], tmp_path, python=False)
    assert done.returncode == 2
    assert "a path cannot hold a NUL byte" in one_error_line(done.stderr)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("python", [False, True], ids=["sim_loop", "python"])
def test_a_failed_run_keeps_the_users_link_to_a_missing_folder(tmp_path, python):
    (tmp_path / "out").symlink_to(tmp_path / "missing")
    done = run_command(["--steps", "10", "--no-rerun", "--out", "out"], tmp_path, python=python)
    assert done.returncode == 2
    assert "a symbolic link to" in one_error_line(done.stderr) and "which does not exist" in done.stderr
    assert os.readlink(tmp_path / "out") == str(tmp_path / "missing")
    assert not (tmp_path / "missing").exists()


def test_plot_never_writes_through_a_link_planted_at_a_temporary_name(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("the user's file")
    out = tmp_path / "out"
    out.mkdir()
    # The old temporary names, and the new ones' prefix, each a link to the victim.
    for name in (".trajectory.png.tmp", ".trajectory.png.tmpx", ".sweep.png.tmp"):
        (out / name).symlink_to(victim)
    done = run_command(["--steps", "50", "--no-rerun", "--plot", "--out", "out"], tmp_path, python=False)
    assert done.returncode == 0, done.stderr
    assert victim.read_text() == "the user's file"
    assert not (out / "trajectory.png").is_symlink()
    assert (out / "trajectory.png").read_bytes().startswith(b"\x89PNG")
    assert sorted(p.name for p in out.iterdir() if p.name.endswith(".tmp")) == [".sweep.png.tmp", ".trajectory.png.tmp"]


@pytest.mark.parametrize("python", [False, True], ids=["sim_loop", "python"])
def test_a_scene_too_large_to_compile_fails_at_once_within_the_memory_budget(tmp_path, python):
    # 1.6e9 heights, 6.4 GB: under an 8 GB ulimit -v the compile child filled them all (a minute, and the
    # machine's memory) before failing; its budget (half the limit) refuses the allocation at once.
    (tmp_path / "big.xml").write_text(
        '<mujoco><asset><hfield name="h" nrow="40000" ncol="40000" size="1 1 1 1"/></asset>'
        '<worldbody><geom type="hfield" hfield="h"/></worldbody></mujoco>\n'
    )
    cmd = [sys.executable, "-m", "simloop"] if python else [str(sim_loop_exe())]
    started = time.monotonic()
    done = subprocess.run(
        [*cmd, "--model", "big.xml", "--out", "out"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=120,
        preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_AS, (8 << 30, 8 << 30)),
    )
    assert time.monotonic() - started < 20
    assert done.returncode in (1, 2), done.stderr[-2000:]
    assert "big.xml" in one_error_line(done.stderr) and "memory" in done.stderr.lower(), done.stderr
    assert not (tmp_path / "out").exists()


def test_more_envs_than_memory_holds_are_refused_before_any_is_made():
    pytest.importorskip("gymnasium")
    import simloop
    import simloop.gym

    started = time.monotonic()
    with pytest.raises(
        ValueError,
        match=r"^1048576 episodes need 1048576 x \d+ KiB of MuJoCo data, more than the \d+ "
        r"MiB allowed \(half of the machine's memory or the process's limit\)",
    ):
        simloop.gym.ScenarioVectorEnv(simloop.Scenario.chapter(), num_envs=1 << 20)  # was killed by the kernel
    assert time.monotonic() - started < 10


def test_the_batch_command_never_writes_through_a_link_planted_at_a_temporary_name(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("the user's file")
    done = run_python(f"""
        import os, sys
        os.chdir({str(tmp_path)!r})
        # The file's temporary is named for the batch's process (the parts' temporaries: the next test).
        os.symlink({str(victim)!r}, f".b.parquet.tmp.{{os.getpid()}}")
        from simloop.batch_command import batch_command
        sys.exit(batch_command(["--seeds", "0:4", "--steps", "50", "--chunk-size", "2", "--out", "b.parquet"]))
    """)
    assert done.returncode == 0, done.stderr[-2000:]
    assert victim.read_text() == "the user's file"
    assert (tmp_path / "b.parquet").is_file() and not (tmp_path / "b.parquet").is_symlink()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.parquet", "victim.txt"]


def test_a_write_is_never_through_a_link_even_one_planted_after_the_look(tmp_path):
    from simloop import parquet_batch

    victim = tmp_path / "victim.txt"
    victim.write_text("the user's file")
    target = tmp_path / "m.json"
    real_unlink = os.unlink

    def unlink_then_plant(path, *args, **kwargs):  # a link planted between the removal and the create
        real_unlink(path, *args, **kwargs)
        os.symlink(victim, path)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(parquet_batch.os, "unlink", unlink_then_plant)
        os.symlink(victim, f"{target}.tmp.{os.getpid()}")
        with pytest.raises(FileExistsError):
            parquet_batch._write_atomically(str(target), lambda out: out.write(b"{}"))
    assert victim.read_text() == "the user's file" and not target.exists()


UNDER_A_GIGABYTE = [  # (file to write or None, its text, the command's arguments, words of its one line)
    ("dd.toml", DEEP_HEADER, ["--scenario", "dd.toml"], "more than 64 dotted parts"),
    (None, "", ["--scenario", "/dev/zero"], "is a device, a pipe or a socket"),
    (
        "z.toml",
        'steps = 10\n[[control]]\nactuator = "push_motor"\ncsv = "/dev/zero"\n',
        ["--scenario", "z.toml"],
        "is a device, a pipe or a socket",
    ),
    (
        "big.xml",
        '<mujoco><asset><hfield name="h" nrow="40000" ncol="40000" size="1 1 1 1"/></asset>'
        '<worldbody><geom type="hfield" hfield="h"/></worldbody></mujoco>\n',
        ["--model", "big.xml"],
        "memory",
    ),
]


@pytest.mark.parametrize("python", [False, True], ids=["sim_loop", "python"])
@pytest.mark.parametrize("name, text, args, words", UNDER_A_GIGABYTE, ids=["deep-key", "dev-zero", "csv", "hfield"])
def test_under_ulimit_v_one_gigabyte_each_input_ends_in_one_line(tmp_path, python, name, text, args, words):
    if name:
        (tmp_path / name).write_text(text)
    cmd = [sys.executable, "-m", "simloop"] if python else [str(sim_loop_exe())]
    started = time.monotonic()
    done = subprocess.run(
        [*cmd, *args, "--out", "out"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=120,
        preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_AS, (10**9, 10**9)),
    )
    assert time.monotonic() - started < 60
    assert done.returncode in (1, 2), done.stderr[-2000:]
    assert words in one_error_line(done.stderr).lower(), done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ([name] if name else [])
