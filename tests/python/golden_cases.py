"""What tests/golden pins, and how each output is turned into bytes.

Shared by scripts/make_goldens.py, which writes the goldens, and
test_goldens.py, which checks both commands and the Python API against them,
so the two cannot drift apart. Everything here is plain Python: no pytest.

Layout: tests/golden/mujoco-X.Y.Z/ per MuJoCo version (MuJoCo is bitwise
reproducible for one build, not across versions), holding manifest.json
(each run's command line or call, and each output's sha256 and size), the
smoke runs' files whole (smoke/), and three stdouts as text (stdout/).
"""

from __future__ import annotations

import hashlib
import json
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Tuple

ROOT = Path(__file__).resolve().parents[2]
GOLDEN_ROOT = ROOT / "tests" / "golden"
OUT = "out"  # every command writes to this relative --out, so its stdout names no machine's path


def golden_dir(mujoco_version: str) -> Path:
    """'MuJoCo 2.2.2' -> tests/golden/mujoco-2.2.2."""
    return GOLDEN_ROOT / mujoco_version.strip().lower().replace(" ", "-")


def sim_loop_mujoco(exe: Path) -> str:
    """The MuJoCo sim_loop runs on, from `sim_loop --version` ('sim_loop 0.1.0 (MuJoCo 2.2.2)')."""
    text = subprocess.run([str(exe), "--version"], capture_output=True, text=True, check=True, timeout=60).stdout
    found = re.search(r"\((MuJoCo [^)]+)\)", text)
    if not found:
        raise RuntimeError(f"{exe} --version names no MuJoCo: {text!r}")
    return found.group(1)


@dataclass(frozen=True)
class CommandRun:
    """One command line, run by sim_loop and by python -m simloop in an empty
    scratch folder (scratch()), writing to --out out."""

    name: str
    args: Tuple[str, ...]  # without --out
    outputs: Tuple[str, ...] = ("metrics.json", "trajectory.csv")
    whole: bool = False  # keep the output files whole (else their sha256)
    stdout_text: bool = False  # keep the stdout as text (else its sha256)
    # What python -m simloop adds: --no-rerun skips its recording (~0.6 s) but where
    # the recording's run is pinned too; a sweep records nothing and refuses the flag.
    python_extra: Tuple[str, ...] = ("--no-rerun",)
    api: Optional[Tuple[str, Dict[str, Any]]] = None  # the same run through the API: (function, kwargs)

    def argv(self) -> List[str]:
        return [*self.args, "--out", OUT]

    def python_argv(self) -> List[str]:
        return [*self.argv(), *self.python_extra]

    def python_records(self) -> bool:
        """Whether python -m simloop writes sim_loop.rrd on this command line."""
        return self.args[0] != "sweep" and "--no-rerun" not in self.python_extra

    def command(self, python: bool = False) -> str:
        return shlex.join(["python", "-m", "simloop", *self.python_argv()] if python else ["sim_loop", *self.argv()])

    def api_call(self) -> str:
        assert self.api is not None
        function, kwargs = self.api
        args = [repr(kwargs["scenario"])] if "scenario" in kwargs else []
        args += [f"{k}={v!r}" for k, v in kwargs.items() if k != "scenario"]
        return f"simloop.{function}({', '.join(args)}).write({OUT!r})"


def _smoke(seed: int, rng: str) -> CommandRun:
    args = ("--smoke", "--seed", str(seed)) + (("--rng", rng) if rng != "mt19937_64" else ())
    return CommandRun(f"smoke-seed{seed}-{rng}", args, whole=True, api=("run", dict(smoke=True, seed=seed, rng=rng)))


def _scenario(scene: str, perturb: bool) -> CommandRun:
    path = f"tests/scenes/{scene}.toml"
    return CommandRun(
        f"scenario-{scene}" + ("" if perturb else "-no-perturb"),
        ("--scenario", path) + (() if perturb else ("--no-perturb",)),
        # With its recording python -m simloop writes a scenario's CSV by another path
        # (run_scenario_drawn): pinned once, for PushT.
        python_extra=() if scene == "pusht" else ("--no-rerun",),
        api=("run_scenario", dict(scenario=path, perturb=perturb)),
    )


COMMAND_RUNS: List[CommandRun] = [
    *(_smoke(seed, rng) for rng in ("mt19937_64", "numpy") for seed in range(4)),
    CommandRun("seed0", ("--seed", "0"), stdout_text=True, python_extra=(), api=("run", dict(seed=0))),
    CommandRun("no-perturb", ("--no-perturb",), api=("run", dict(perturb=False))),
    CommandRun(
        "break-it",
        ("--timestep", "0.05", "--no-perturb"),
        stdout_text=True,
        api=("run", dict(timestep=0.05, perturb=False)),
    ),
    CommandRun("energy-audit", ("--energy-audit",), api=("run", dict(audit_energy=True))),
    CommandRun("record-every-7", ("--record-every", "7"), api=("run", dict(record_every=7))),
    CommandRun("steps-1", ("--steps", "1"), api=("run", dict(steps=1))),
    CommandRun("sweep", ("sweep",), outputs=("sweep.csv",), stdout_text=True, python_extra=(), api=("sweep", {})),
    *(_scenario(scene, perturb) for scene in ("pusht", "walker", "arm_push") for perturb in (True, False)),
]


def scratch(path: Path) -> Path:
    """An empty folder to run in, with a link `tests` to the repository's
    tests/, so that `--scenario tests/scenes/pusht.toml --out out` reads as
    from the repository's root and writes nowhere in it."""
    path.mkdir(parents=True, exist_ok=True)
    (path / "tests").symlink_to(ROOT / "tests", target_is_directory=True)
    return path


def run_command(run: CommandRun, program: List[str], cwd: Path, python: bool) -> Tuple[str, Dict[str, bytes]]:
    """Runs `program ARGS` in cwd (python -m simloop: with its python_extra).
    Returns its stdout and its outputs' bytes; raises on a non-zero exit."""
    argv = run.python_argv() if python else run.argv()
    done = subprocess.run([*program, *argv], cwd=cwd, capture_output=True, stdin=subprocess.DEVNULL, timeout=300)
    if done.returncode != 0:
        raise RuntimeError(
            f"`{shlex.join(program + argv)}` exited {done.returncode}: {done.stderr.decode(errors='replace').strip()}"
        )
    return done.stdout.decode(), {name: (cwd / OUT / name).read_bytes() for name in run.outputs}


def pinned_stdout(stdout: str, python: bool) -> str:
    """The stdout with what may not be pinned taken out: the wall-clock line
    (a time and a memory figure); for python -m simloop, the recording line,
    which names its viewer by this machine's venv path (sim_loop's own says
    'recording: none ...' and is pinned)."""
    dropped = ("wall-clock:", "recording:") if python else ("wall-clock:",)
    return "".join(line for line in stdout.splitlines(keepends=True) if not line.startswith(dropped))


def run_api(run: CommandRun, out: Path) -> Dict[str, bytes]:
    """The same run through the Python API, written with .write(out)."""
    import simloop

    assert run.api is not None
    function, kwargs = run.api
    if "scenario" in kwargs:  # a path from the repository's root
        kwargs = {**kwargs, "scenario": str(ROOT / kwargs["scenario"])}
    getattr(simloop, function)(**kwargs).write(out)
    return {name: (out / name).read_bytes() for name in run.outputs}


def file_entry(data: bytes) -> Dict[str, Any]:
    return {"sha256": hashlib.sha256(data).hexdigest(), "bytes": len(data)}


# ---- Python API cases: each returns its parts as {name: numpy array or text} ----

PUSHT = "tests/scenes/pusht.toml"
# A fixed action sequence of exact binary fractions (no libm: the same bits on any machine).
ACTIONS = [(1.0, 0.0), (0.5, 0.25), (0.75, -0.5), (-0.25, 1.0), (1.0, 0.5), (0.0, -1.0), (0.5, 0.5)]


def pusht_policy(obs: Any) -> List[float]:
    """Steers the T-block towards (0.6, 0.3): plain float arithmetic, deterministic."""
    return [max(-1.0, min(1.0, 4.0 * (0.6 - obs["tblock_x"]))), max(-1.0, min(1.0, 3.0 * (0.3 - obs["tblock_y"])))]


def _policy_run() -> Dict[str, Any]:
    import simloop

    result = simloop.run_scenario(str(ROOT / PUSHT), seed=0, policy=pusht_policy, control_every=7)
    return {"column_names": list(result.column_names), "trajectory": result.trajectory, "metrics": result.metrics}


def _gym_episodes() -> Dict[str, Any]:
    import numpy as np
    from simloop.gym import ScenarioEnv

    x = -1  # tblock_x's place in the observation, known once the env is made

    def reward(obs: Any, action: Any, next_obs: Any) -> float:
        return float(next_obs[x]) - float(obs[x]) - 0.01 * (float(action[0]) ** 2 + float(action[1]) ** 2)

    env = ScenarioEnv(str(ROOT / PUSHT), control_every=10, reward=reward)
    x = env.observation_names.index("tblock_x")
    obs, rewards, flags, steps, times, seeds = [], [], [], [], [], []
    # Episode 1 seeded and run to its end (truncated); episode 2 unseeded: its
    # seed is drawn from the env's np_random, as a seeded sequence repeats.
    for seed, decisions in ((5, None), (None, 20)):
        o, info = env.reset(seed=seed)
        obs.append(o)
        seeds.append(info["seed"])
        k = 0
        while decisions is None or k < decisions:
            o, r, terminated, truncated, info = env.step(ACTIONS[k % len(ACTIONS)])
            obs.append(o)
            rewards.append(r)
            flags.append((terminated, truncated))
            steps.append(info["step"])
            times.append(info["time"])
            k += 1
            if terminated or truncated:
                break
    env.close()
    return {
        "observation_names": list(env.observation_names),
        "episode_seeds": np.array(seeds, dtype=np.uint64),
        "observations": np.stack(obs),
        "rewards": np.array(rewards),
        "terminated_truncated": np.array(flags),
        "steps": np.array(steps, dtype=np.int64),
        "times": np.array(times),
    }


def _table(table: Any) -> Dict[str, Any]:
    return {"column_names": table.column_names, **{f"column {name}": table[name] for name in table.column_names}}


def _batch_chapter() -> Dict[str, Any]:
    import simloop

    return _table(simloop.run_batch(seeds=range(4), metrics_only=True))


def _batch_pusht() -> Dict[str, Any]:
    import simloop

    return _table(simloop.run_scenario_batch(str(ROOT / PUSHT), seeds=range(3), metrics_only=True))


@dataclass(frozen=True)
class ApiCase:
    name: str
    call: str  # what it runs, for the manifest's reader
    parts: Callable[[], Dict[str, Any]] = field(compare=False)


API_CASES: List[ApiCase] = [
    ApiCase(
        "policy-pusht",
        f"simloop.run_scenario({PUSHT!r}, seed=0, policy=golden_cases.pusht_policy, control_every=7)",
        _policy_run,
    ),
    ApiCase(
        "gym-pusht",
        f"simloop.gym.ScenarioEnv({PUSHT!r}, control_every=10, reward=...): reset(seed=5), "
        "golden_cases.ACTIONS cycled to truncation, reset(), 20 more steps (golden_cases._gym_episodes)",
        _gym_episodes,
    ),
    ApiCase(
        "batch-table-chapter", "simloop.run_batch(seeds=range(4), metrics_only=True): every column", _batch_chapter
    ),
    ApiCase(
        "batch-table-pusht",
        f"simloop.run_scenario_batch({PUSHT!r}, seeds=range(3), metrics_only=True): every column",
        _batch_pusht,
    ),
]


def part_entry(value: Any) -> Dict[str, Any]:
    """A part's digest: a numpy array by dtype, shape and raw bytes (strings
    and objects as JSON), anything else as JSON (floats written exactly)."""
    import numpy as np

    if isinstance(value, np.ndarray):
        if value.dtype == object:
            data = json.dumps(value.tolist()).encode()
        else:
            data = np.ascontiguousarray(value).tobytes()
        return {"dtype": str(value.dtype), "shape": list(value.shape), **file_entry(data)}
    return {"json": True, **file_entry(json.dumps(value, sort_keys=True).encode())}


def load_manifest(directory: Path) -> Dict[str, Any]:
    with open(directory / "manifest.json") as f:
        manifest: Dict[str, Any] = json.load(f)
    return manifest


def python_program() -> List[str]:
    """python -m simloop, with this interpreter (the venv's, for the tests and the script)."""
    return [sys.executable, "-m", "simloop"]
