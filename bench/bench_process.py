#!/usr/bin/env python3
"""The whole process `sim_loop --seed 0`, its files written, against a bare C
program doing the same run on the same library (build/bare_chapter): wall-clock,
CPU time, peak memory and instructions, and their ratios (target: at most 1.10
in instructions and CPU time).

    python3 bench/bench_process.py [--build build] [--runs 21] [--instruction-runs 3] [--bare-csv]

What "the same run" is, and why this is the fair comparison:

- Both load the chapter's scene from the same XML text (cpp/chapter_scene.cc's; CMake
  copies it into bare_chapter) through a one-file virtual file system, on the
  same libmujoco, set ctrl[0] = 1, apply seed 0's shove in its window (its
  start, length and force read from sim_loop's trajectory.csv and given to the
  bare program) and take the same 2,000 mj_steps.
- Both write the run's files into an empty folder: metrics.json, the same
  bytes, and every row of the trajectory, the same 2,001 rows of 22 numbers.
  Both are checked before timing: the metrics byte for byte, the rows bit for
  bit. sim_loop writes the rows as CSV text (the shortest text that reads back
  exactly); the bare program writes them as raw doubles (trajectory.f64), the
  cheapest exact form plain C has. C's only exact text is printf's, which costs
  about ten times what sim_loop's formatting costs per number: a bare program
  writing CSV with printf is slower than sim_loop, and the ratio would measure
  glibc, not simloop. Against raw doubles the ratio counts everything sim_loop
  adds, its CSV text included: startup, flags, the library around the loop,
  the text, the atomic outputs and the folder's lock, the report. --bare-csv
  adds that printf("%.17g") CSV program as a third column, for reference.
- Each run is a fresh process started by build/rusage_run (so that its peak
  memory is its own: Linux keeps, across exec, the peak of the process that
  forked, and Python's is larger), stdout to a pipe, in a fresh empty folder.
  Rounds alternate which program goes first. The machines are shared and
  noisy: medians, CPU time (user + sys) beside wall-clock, and each round's
  ratio paired, the median of those printed.
- Instructions: `perf stat -e instructions` where the machine lets perf count
  them, else valgrind's callgrind (the whole process, from the dynamic
  loader's first instruction; --instruction-runs runs each, median). The
  script says which, or that neither is there. Instructions do not move with
  the machine's load; CPU time does.
"""

import argparse
import json
import math
import os
import re
import shutil
import statistics
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

TARGET = 1.10
COLUMNS = 22


def measured(argv: list[str], rusage_run: Path) -> dict:
    """One run under rusage_run: wall, user, sys (seconds), maxrss (KiB)."""
    proc = subprocess.run([str(rusage_run), *argv], capture_output=True, text=True)
    lines = proc.stderr.strip().splitlines()
    match = re.fullmatch(
        r"rusage_run: status (\d+) wall (\S+) user (\S+) sys (\S+) maxrss_kib (\d+)", lines[-1] if lines else ""
    )
    if not match:
        sys.exit(f"{argv[0]}: no measurement: {proc.stderr.strip()!r}")
    if match.group(1) != "0":
        sys.exit(f"{' '.join(argv)} failed (status {match.group(1)}): {proc.stderr.strip()}")
    wall, user, sys_time = (float(match.group(i)) for i in (2, 3, 4))
    return {"wall": wall, "cpu": user + sys_time, "rss": int(match.group(5)) / 1024.0}


def read_csv_rows(path: Path) -> tuple[list[str], list[list[float]]]:
    lines = path.read_text().splitlines()
    rows = [[float(v) if v else math.nan for v in line.split(",")] for line in lines[1:]]
    return lines[0].split(","), rows


def same_bits(a: float, b: float) -> bool:
    return struct.pack("<d", a) == struct.pack("<d", b) or (math.isnan(a) and math.isnan(b))


def shove_of(header: list[str], rows: list[list[float]], csv_text: str) -> tuple[int, int, str]:
    """The shove sim_loop applied: (start step, steps, force in y as its CSV wrote it)."""
    col = header.index("shove_y")
    pushed = [r for r in rows if not math.isnan(r[col]) and r[col] != 0.0]
    if not pushed:
        return len(rows), 0, "0"
    texts = [line.split(",")[col] for line in csv_text.splitlines()[1:]]
    return int(pushed[0][0]), len(pushed), texts[int(pushed[0][0])]


def check_same_run(sim_dir: Path, bare_dir: Path, csv: bool) -> None:
    """The bare program's files hold what sim_loop's hold (or sys.exit)."""
    if (sim_dir / "metrics.json").read_bytes() != (bare_dir / "metrics.json").read_bytes():
        sys.exit(
            f"metrics.json differ:\n{(sim_dir / 'metrics.json').read_text()}\n{(bare_dir / 'metrics.json').read_text()}"
        )
    _, sim_rows = read_csv_rows(sim_dir / "trajectory.csv")
    if csv:
        _, bare_rows = read_csv_rows(bare_dir / "trajectory.csv")
    else:
        raw = (bare_dir / "trajectory.f64").read_bytes()
        values = struct.unpack(f"<{len(raw) // 8}d", raw)
        bare_rows = [list(values[i : i + COLUMNS]) for i in range(0, len(values), COLUMNS)]
    if len(sim_rows) != len(bare_rows):
        sys.exit(f"trajectory: sim_loop wrote {len(sim_rows)} rows, the bare program {len(bare_rows)}")
    for i, (a, b) in enumerate(zip(sim_rows, bare_rows)):
        if len(a) != len(b) or not all(same_bits(x, y) for x, y in zip(a, b)):
            sys.exit(f"trajectory row {i} differs:\n  sim_loop {a}\n  bare     {b}")


def perf_can_count() -> bool:
    if not shutil.which("perf"):
        return False
    proc = subprocess.run(["perf", "stat", "-x,", "-e", "instructions:u", "true"], capture_output=True, text=True)
    return proc.returncode == 0 and re.match(r"\d+,", proc.stderr.strip().splitlines()[-1] if proc.stderr else "")


def count_instructions(argv: list[str], tool: str, scratch: Path) -> int:
    if tool == "perf":
        proc = subprocess.run(["perf", "stat", "-x,", "-e", "instructions:u", *argv], capture_output=True, text=True)
        return int(proc.stderr.strip().splitlines()[-1].split(",")[0])
    out = scratch / "callgrind.out"
    subprocess.run(
        ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", *argv], check=True, capture_output=True
    )
    match = re.search(r"^(?:summary|totals): (\d+)", out.read_text(), re.MULTILINE)
    if not match:
        sys.exit(f"callgrind: no totals in {out}")
    out.unlink()
    return int(match.group(1))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", type=Path, default=Path("build"), help="CMake build directory")
    parser.add_argument("--runs", type=int, default=21, help="timed runs of each program (default 21)")
    parser.add_argument(
        "--instruction-runs",
        type=int,
        default=3,
        help="runs of each under the instruction counter (default 3; 0: none)",
    )
    parser.add_argument(
        "--bare-csv",
        action="store_true",
        help="also the bare program writing its CSV with printf (slower than sim_loop)",
    )
    args = parser.parse_args()
    sim_loop, bare, rusage_run = (args.build / name for name in ("sim_loop", "bare_chapter", "rusage_run"))
    for exe in (sim_loop, bare, rusage_run):
        if not exe.exists():
            sys.exit(
                f"--build: {exe} not found; build first (README; bare_chapter and rusage_run are "
                "built with SIMLOOP_BUILD_BENCH, on by default)"
            )

    with tempfile.TemporaryDirectory(prefix="bench_process.") as tmp:
        scratch = Path(tmp)
        # Once, untimed: sim_loop's run, its shove, and the bare program's files checked against it.
        first = scratch / "first"
        subprocess.run([str(sim_loop), "--seed", "0", "--out", str(first / "sim")], check=True, capture_output=True)
        csv_text = (first / "sim" / "trajectory.csv").read_text()
        header, rows = read_csv_rows(first / "sim" / "trajectory.csv")
        steps = json.loads((first / "sim" / "metrics.json").read_text())["steps"]
        start, count, force = shove_of(header, rows, csv_text)
        programs = {"sim_loop": lambda out: [str(sim_loop), "--seed", "0", "--out", str(out)]}
        formats = ["binary"] + (["csv"] if args.bare_csv else [])
        for fmt in formats:
            name = "bare" if fmt == "binary" else "bare csv"
            programs[name] = lambda out, fmt=fmt: [
                str(bare),
                str(out),
                str(steps),
                str(start),
                str(count),
                force,
                "0",
                fmt,
            ]
            (first / fmt).mkdir()
            subprocess.run(programs[name](first / fmt), check=True, capture_output=True)
            check_same_run(first / "sim", first / fmt, fmt == "csv")
        print(
            f"sim_loop --seed 0 against build/bare_chapter: {steps} steps, shove {force} N in y at steps "
            f"{start} to {start + count - 1}; metrics.json the same bytes, the trajectory's rows the same bits"
        )
        names = list(programs)

        # Timed: fresh empty folders, rounds alternating the order.
        load_before = os.getloadavg()[0]
        results: dict[str, list[dict]] = {name: [] for name in names}
        for run in range(args.runs):
            order = names if run % 2 == 0 else names[::-1]
            for name in order:
                out = scratch / f"run-{run}-{name.replace(' ', '-')}"
                out.mkdir()
                results[name].append(measured(programs[name](out), rusage_run))
                shutil.rmtree(out)
        load_after = os.getloadavg()[0]

        # Instructions.
        tool = "perf" if perf_can_count() else "callgrind" if shutil.which("valgrind") else None
        instructions: dict[str, int] = {}
        if tool and args.instruction_runs > 0:
            for name in names:
                counts = []
                for run in range(args.instruction_runs):
                    out = scratch / f"count-{run}-{name.replace(' ', '-')}"
                    out.mkdir()
                    counts.append(count_instructions(programs[name](out), tool, scratch))
                    shutil.rmtree(out)
                instructions[name] = int(statistics.median(counts))

    def med(name: str, key: str) -> float:
        return statistics.median(r[key] for r in results[name])

    def paired(name: str, key: str) -> float:
        return statistics.median(s[key] / b[key] for s, b in zip(results["sim_loop"], results[name]))

    print(f"{args.runs} runs each, alternating; load average {load_before:.2f} before, {load_after:.2f} after")
    for other in names[1:]:
        label = "bare (rows as raw doubles)" if other == "bare" else "bare (CSV by printf %.17g)"
        print(f"\n  sim_loop against {label}")
        print(f"  {'':24}{'sim_loop':>12}{'bare':>12}{'ratio':>9}  target")
        for key, what, unit, scale in (("wall", "wall-clock", "ms", 1e3), ("cpu", "CPU (user+sys)", "ms", 1e3)):
            print(
                f"  {what + ' median':24}{med('sim_loop', key) * scale:9.1f} {unit}{med(other, key) * scale:9.1f} "
                f"{unit}{paired(other, key):9.3f}  {'<= %.2f' % TARGET if key == 'cpu' else ''}"
            )
        print(
            f"  {'peak memory median':24}{med('sim_loop', 'rss'):8.1f} MiB{med(other, 'rss'):8.1f} MiB"
            f"{med('sim_loop', 'rss') / med(other, 'rss'):9.3f}"
        )
        if instructions:
            print(
                f"  {'instructions (' + tool + ')':24}{instructions['sim_loop'] / 1e6:10.1f} M"
                f"{instructions[other] / 1e6:10.1f} M{instructions['sim_loop'] / instructions[other]:9.3f}"
                f"  <= {TARGET:.2f}"
            )
    print("\n  (ratios: wall and CPU the median of each round's sim_loop / bare; memory and instructions of medians)")
    if not tool:
        print(
            "  instructions: not measured: perf cannot count them on this machine and valgrind is not "
            "installed (apt-get install valgrind)"
        )
    elif args.instruction_runs > 0:
        print(
            f"  instructions: {tool}, median of {args.instruction_runs} runs each"
            + ("" if tool == "perf" else " (perf cannot count instructions on this machine)")
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
