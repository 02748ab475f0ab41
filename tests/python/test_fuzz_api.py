"""The Python API under seeded misuse: a few hundred wrong calls, each refused
with one line of a documented exception, and never a crash (api_fuzz.py)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

FUZZ = Path(__file__).with_name("api_fuzz.py")


@pytest.mark.parametrize("seed", [1, 2])
def test_api_misuse_is_refused_in_one_line_and_never_crashes(tmp_path, seed):
    proc = subprocess.run(
        [sys.executable, str(FUZZ), str(seed), "400"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=120,
    )
    assert proc.returncode == 0, f"the interpreter died (exit {proc.returncode}): {proc.stderr[-2000:]}"
    report = json.loads(proc.stdout)
    assert report["calls"] == 400
    assert report["bad"] == []
    # The misuse was refused, not waved through.
    assert sum(report["raised"].values()) > 300
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()
