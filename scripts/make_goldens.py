#!/usr/bin/env python3
"""Regenerates tests/golden/mujoco-X.Y.Z/ from the code as it is now.

    .venv/bin/python scripts/make_goldens.py [--sim-loop build/sim_loop]

The goldens pin what users can observe (the commands' files and stdout, the
Python API's arrays), so that a change which should change nothing can prove
it (tests/python/test_goldens.py). Run this script ONLY for an intended
change of outputs, never to make a failing golden test pass, and say in the
commit what changed and why (a new column, a fixed bug in the shove, a new
MuJoCo version's table). Tests never run it.

It writes the folder of the MuJoCo that build/sim_loop and this Python's
simloop were built against (they must agree), from scratch: a run that is no
longer listed in tests/python/golden_cases.py leaves no file behind. Outputs
come from sim_loop; python -m simloop and the API must give the same bytes
first, or nothing is written (a disagreement is a bug, not a golden).
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "python"))
import golden_cases as g  # noqa: E402

ABOUT = (
    "Outputs of the code at the commit that wrote this file, on the MuJoCo named here; "
    "made by scripts/make_goldens.py, checked by tests/python/test_goldens.py."
)
HOW = {
    "commands": f"each command line runs in an empty folder holding a link 'tests' to the repository's tests/, "
    f"so paths read as from the repository's root; --out is the relative '{g.OUT}', so the lines naming "
    "the outputs (metrics:, trajectory:, sweep:) hold no machine's path and are pinned as printed",
    "python -m simloop": "the same command line, plus --no-rerun where 'python -m simloop' says so (its recording "
    "is not byte-reproducible: rerun stamps time-based ids); it must write the same bytes",
    "stdout": "sim_loop's stdout without its 'wall-clock:' line (time and peak memory); 'python -m simloop stdout': "
    "python's without that line and its 'recording:' line (which names the viewer by the venv's path), "
    "the same text as sim_loop's without its 'recording: none ...' line",
    "files": "sha256 and size of each output; 'file' or 'text' names a copy kept whole in this folder",
    "api": "parts of a Python API result: numpy arrays by dtype, shape and the sha256 of their raw bytes "
    "(object arrays as JSON); lists and dicts as json.dumps(sort_keys=True)",
}


def fail(message: str) -> None:
    sys.exit(f"make_goldens: {message}")


def same(what: str, ours: dict, theirs: dict) -> None:
    for name in ours:
        if ours[name] != theirs[name]:
            fail(f"{what}: {name} differs from sim_loop's; fix that first (nothing was written)")


def dump(value: object, indent: int = 0) -> str:
    """JSON, one line per output's digest (a dict holding "sha256"), so the manifest reads as a table."""
    if isinstance(value, dict) and value and "sha256" not in value:
        pad = " " * (indent + 1)
        items = [f"{pad}{json.dumps(k)}: {dump(v, indent + 1)}" for k, v in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + " " * indent + "}"
    return json.dumps(value)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sim-loop", type=Path, default=g.ROOT / "build" / "sim_loop")
    args = parser.parse_args()
    try:
        import simloop
    except ImportError:
        fail(f"{sys.executable} has no simloop: run this with the project's .venv/bin/python")
    version = g.sim_loop_mujoco(args.sim_loop)
    if version != simloop.MUJOCO_VERSION:
        fail(f"{args.sim_loop} runs on {version} but simloop on {simloop.MUJOCO_VERSION}: build both alike")
    target = g.golden_dir(version)
    manifest: dict = {
        "about": ABOUT,
        "mujoco": version,
        "simloop": simloop.__version__,
        "how": HOW,
        "commands": {},
        "api": {},
    }
    keep: dict = {}  # relative path -> bytes, written only once everything agreed
    with tempfile.TemporaryDirectory() as tmp:
        for i, run in enumerate(g.COMMAND_RUNS):
            print(f"{run.command()}", flush=True)
            stdout, files = g.run_command(run, [str(args.sim_loop)], g.scratch(Path(tmp) / f"c{i}"), python=False)
            py_stdout, py_files = g.run_command(run, g.python_program(), g.scratch(Path(tmp) / f"p{i}"), python=True)
            same(f"python -m simloop {run.name}", files, py_files)
            if g.pinned_stdout(stdout, python=True) != g.pinned_stdout(py_stdout, python=True):
                fail(f"python -m simloop {run.name}: stdout differs from sim_loop's (nothing was written)")
            if run.api is not None:
                same(run.api_call(), files, g.run_api(run, Path(tmp) / f"a{i}"))
            entry: dict = {"command": run.command(), "python -m simloop": run.command(python=True), "files": {}}
            if run.api is not None:
                entry["api"] = run.api_call()
            for name, data in files.items():
                entry["files"][name] = g.file_entry(data)
                if run.whole:
                    rel = f"smoke/{run.name.removeprefix('smoke-')}/{name}"
                    entry["files"][name]["file"] = rel
                    keep[rel] = data
            text = g.pinned_stdout(stdout, python=False)
            entry["stdout"] = g.file_entry(text.encode())
            entry["python -m simloop stdout"] = g.file_entry(g.pinned_stdout(py_stdout, python=True).encode())
            if run.stdout_text:
                entry["stdout"]["text"] = f"stdout/{run.name}.txt"
                keep[f"stdout/{run.name}.txt"] = text.encode()
            manifest["commands"][run.name] = entry
        for case in g.API_CASES:
            print(case.call, flush=True)
            parts = case.parts()
            if {k: g.part_entry(v) for k, v in case.parts().items()} != {k: g.part_entry(v) for k, v in parts.items()}:
                fail(f"{case.name}: two calls in one process differ (not deterministic; nothing was written)")
            manifest["api"][case.name] = {"call": case.call, "parts": {k: g.part_entry(v) for k, v in parts.items()}}
    if target.exists():
        shutil.rmtree(target)
    for rel, data in keep.items():
        (target / rel).parent.mkdir(parents=True, exist_ok=True)
        (target / rel).write_bytes(data)
    (target / "manifest.json").write_text(dump(manifest) + "\n")
    print(
        f"wrote {target.relative_to(g.ROOT)}: {len(manifest['commands'])} command lines, "
        f"{len(manifest['api'])} API cases"
    )


if __name__ == "__main__":
    main()
