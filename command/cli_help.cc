// The commands' --help texts: the run's and the sweep's.
#include <string>
#include <string_view>

#include "cli_options.hpp"

namespace simloop::cli {

std::string help_text(std::string_view program, std::string_view recording) {
  std::string text = "usage: " + std::string(program) + R"( [options]

The chapter's MuJoCo simulation loop (ch0.1-sim-loop): a box on a floor, a
pusher on a slide joint at full throttle, and a seeded sideways shove on the
box halfway through. Writes metrics.json and trajectory.csv into --out.

options:
  --chapter         the book's run as closely as this build allows: the shove
                    drawn as the chapter draws it (--rng numpy: +9.8 N for
                    seed 0, as the book prints)
  --seed N          seeds the shove direction and strength (0 .. 2^64-1; default 0)
  --rng NAME        the generator that draws the shove: mt19937_64 (default,
                    std::mt19937_64) or numpy (the chapter's
                    np.random.default_rng(seed), PCG64; numpy not needed)
  --steps N         steps to run (default 2000)
  --timestep S      sim seconds per mj_step (default 0.002; 0.05 breaks it)
  --smoke           fixed 300-step run for CI; two runs match byte for byte
  --out DIR         output directory (default outputs/ch0.1-sim-loop)
  --no-perturb      skip the shove: the baseline run
  --plot            also draw trajectory.png (x of the pusher and the box, box
                    y and z, contacts; the shove shaded; for a scenario, each
                    recorded body's x, y, z and speed, contacts, disturbances
                    shaded), with matplotlib through the Python package
  --video FILE      also make a video of the run from MuJoCo's own renderer,
                    offscreen, 25 frames per simulated second: FILE.mp4 with
                    ffmpeg on PATH, else an animated PNG beside it
                    (FILE.png); python -m simloop only
  --energy-audit    account for every joule: energy and work columns in
                    trajectory.csv, totals in the summary
  --record-every K  write every K-th step to trajectory.csv (default 1; the
                    final state is always written)
  --model FILE      another MJCF scene, at its own timestep unless --timestep
                    is given (default: the chapter's pusher scene). Alone it
                    runs the chapter's loop: a body "box" on a free joint and
                    an actuator 0 on a slide or hinge joint; a scene with
                    nothing to push (no body a force can move, no actuator)
                    runs as it is
  --body BODY       the body (a name or an index) the chapter's shove acts on
                    (default box; on a --model scene, no shove unless given):
                    runs a scenario on any scene (see below)
  --ctrl ACT=VALUE  drive actuator ACT (a name or an index) at VALUE, held
                    for the whole run; repeatable (default: actuator 0 at 1.0)
  --scenario FILE   a scenario file (TOML): the scene, timestep, length,
                    controls, disturbances and recording, as data
  --rerun, --no-rerun
                    )";
  text += recording;
  text += R"(
  --version         print the version and exit
  -h, --help        print this help and exit

commands:
  sweep             the baseline at many timesteps: where Break It begins
                    (see sweep --help)

scenarios: with --scenario, --body or --ctrl, trajectory.csv has columns named
from the scene (a row per step: the ctrl applied, the forces, each recorded
body's pose and velocity, joints, actuator forces, sensors, contacts) and
metrics.json the scenario's figures; --steps, --timestep, --seed, --rng,
--no-perturb, --smoke and --record-every still apply.

exit status: 0 done, 1 the run failed (MuJoCo error, cannot write outputs),
2 bad command line or input (a flag's value, --model, --scenario, --out).
)";
  return text;
}

std::string sweep_help_text(std::string_view program) {
  return "usage: " + std::string(program) + R"( sweep [options]

Runs the baseline (no shove) at many timesteps over the same span of sim time,
in parallel over one compiled model, with the energy audit on; prints a table,
names the largest stable timestep, and writes sweep.csv into --out.

A timestep is stable when the box's centre never rises more than 5 mm above
its resting height (0.05 m), does not end more than 1 mm below it, and MuJoCo
raised no warning. The largest stable timestep is the largest one below which
every swept timestep is stable.

options:
  --timesteps A,B,...   the timesteps to run (default: 25 round ones, 1, 2, 3,
                        4, 5, 6 and 8 per decade, from 0.0005 to 1)
  --range FROM:TO:N     N timesteps from FROM to TO, log-spaced
  --duration S          sim seconds per run (default 4)
  --threads N           workers (default: one per core)
  --out DIR             output directory (default outputs/ch0.1-sim-loop)
  --model FILE          another MJCF scene (as for the run)
  --plot                also draw sweep.png, with matplotlib through the
                        Python package
  -h, --help            print this help and exit

scenario sweeps: --scenario FILE (or --body NAME, --ctrl ACT=VALUE, with or
without --model, as for a run) sweeps the scenario instead: each timestep runs
it over --duration (default: the scenario's own length) with its controls and
disturbances (seed 0), and the finest timestep is the reference. A timestep
blew up when MuJoCo or simloop_DIVERGED warned, or a recorded body ended more
than 10% of the scene's size (MuJoCo's stat.extent) from where the reference
left it. The default grid drops timesteps that leave a run under 4 steps.
)";
}

}  // namespace simloop::cli
