"""A scenario's runs from Python: run_scenario once, run_scenario_batch over
seeds and timesteps, with the scenario's controls, your own (controls=), or
a policy deciding them (policy=).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Iterable, Optional, Tuple

from . import _core
from ._checks import (
    ModelLike,
    Progress,
    _check_bool,
    _check_int,
    _check_progress,
    _check_real,
    _check_seed,
    _check_str,
    _check_threads,
    _describe,
    _sequence,
)
from .policy import Policy, _check_no_control_every, _decider
from .scenario import ScenarioLike, ScenarioResult, _scenario_and_scene, scenario_config

if TYPE_CHECKING:  # numpy and the tables load when used: `import simloop` stays quick
    import numpy as np

    from .tables import BatchTable


def _inputs_array(name: str, value: object, described: str) -> Optional[np.ndarray]:
    """value as a C-contiguous float64 array (the same array, not a copy,
    when it already is one), or None. Its shape and values are checked by
    the C++ side, which knows the run's steps, actuators and state size."""
    if value is None:
        return None
    import numpy as np

    if isinstance(value, (str, bytes)):
        raise TypeError(f"{name} must be an array of numbers {described}, got {_describe(value)}")
    try:
        array = np.asarray(value)
    except (TypeError, ValueError):  # ragged lists
        raise TypeError(f"{name} must be an array of numbers {described}, got {_describe(value)}") from None
    if array.dtype.kind not in "iuf":
        raise TypeError(f"{name} must be an array of numbers {described}, got an array of dtype {array.dtype}")
    return np.ascontiguousarray(array, dtype=np.float64)


def _batch_inputs(controls: Any, initial_state: Any) -> "Tuple[Optional[np.ndarray], Optional[np.ndarray]]":
    """A batch's controls and initial_state as arrays (_inputs_array), or None."""
    return (
        _inputs_array("controls", controls, "shaped (runs, steps, nu) or (steps, nu)"),
        _inputs_array("initial_state", initial_state, "shaped (runs, state_size) or (state_size,)"),
    )


def run_scenario(
    scenario: ScenarioLike,
    *,
    seed: int = 0,
    rng: str = "mt19937_64",
    timestep: Optional[float] = None,
    steps: Optional[int] = None,
    perturb: bool = True,
    record_every: int = 1,
    model: ModelLike = None,
    progress: Progress = None,
    controls: Any = None,
    initial_state: Any = None,
    policy: Optional[Policy] = None,
    control_every: int = 1,
    audit_energy: bool = False,
) -> ScenarioResult:
    """Runs a scenario (a Scenario or a scenario file's path) once.

    seed draws its random disturbances and nothing else; rng is "mt19937_64"
    or "numpy" as for run(). timestep and steps override the scenario's;
    perturb=False drops its disturbances. model: the scene already compiled
    (scenario.model()), to compile it once for many runs, or another scene
    (a Model, an MJCF file's path, a mujoco.MjModel). Returns a
    ScenarioResult: column_names, trajectory (a read-only numpy view),
    column(name), metrics (a dict), disturbances, params (what its
    [[reset.param]] drew), warnings, final_row,
    final_state (the full state at the end), summary(), write(out).
    Unknown names raise ValueError listing what the scene has.

    controls: your own controls, as mujoco.rollout takes them: a (steps, nu)
    array whose row t is the whole ctrl vector (one value per actuator, in
    the scene's order) written before step t. They replace the scenario's
    controls; its disturbances still apply (perturb=False drops them). The
    rows must match the run's steps exactly (ValueError otherwise) and every
    value must be finite (NaN is refused, not read as "keep"); MuJoCo clamps
    values to ctrlrange as it applies them, and the ctrl columns record what
    it applied. A C-contiguous float64 array is read in place, not copied:
    do not write to it during the call.
    initial_state: start from this full state (time included) instead of the
    scene's reset pose: the flat layout of include/simloop/state.hpp, as
    result.final_state gives it, so a run continued from a result's
    final_state gives the bits of one longer run.

    policy: None (open loop: the scenario's controls), or a callable
    policy(obs) -> ctrl called every `control_every` steps (at steps 0, K,
    2K, ...) with an Observation, returning the ctrl of every actuator (nu
    numbers; a number when nu == 1), which MuJoCo then holds for the next K
    steps. With a policy, ctrl is the policy's on every actuator from step 0
    on: the scenario's controls are not written (its disturbances are). The
    trajectory records the ctrl applied, as always. The C++ loop takes the
    GIL only to call the policy. An exception the policy raises stops the
    run and reaches the caller with "(policy at decision step N)" added to
    its message; a ctrl of the wrong shape or not finite raises ValueError
    naming the decision step.

    audit_energy: account for every joule, as the chapter's run does: the
    energy audit's seven columns after the scenario's own (energy and the
    work of the actuators, the disturbances, passive forces and
    constraints), its totals in result.energy; the physics is unchanged.
    """
    scenario, scene = _scenario_and_scene(scenario, model)
    config = scenario_config(seed, rng, timestep, steps, perturb, record_every, audit_energy)
    own = _inputs_array("controls", controls, "shaped (steps, nu)")
    start = _inputs_array("initial_state", initial_state, "shaped (state_size,)")
    if policy is not None:
        if own is not None or start is not None:
            raise ValueError(
                "policy with controls or initial_state is not supported: the policy decides ctrl, "
                "and its runs start from the scene's reset pose"
            )
        decide, every = _decider(policy, control_every, scene, scenario, config)
        return _core.run_scenario(
            scene, scenario._core, config, decide=decide, control_every=every, progress=_check_progress(progress)
        )
    _check_no_control_every(control_every)
    return _core.run_scenario(
        scene, scenario._core, config, controls=own, initial_state=start, progress=_check_progress(progress)
    )


_POLICY_ALONE = (
    "policy with controls, initial_state or metrics_only is not supported: give the "
    "policy alone (its runs keep their trajectories and start from the reset pose)"
)


def run_scenario_batch(
    scenario: ScenarioLike,
    seeds: Iterable[int] = (0,),
    timesteps: Iterable[Optional[float]] = (None,),
    *,
    rng: str = "mt19937_64",
    steps: Optional[int] = None,
    perturb: bool = True,
    record_every: int = 1,
    model: ModelLike = None,
    threads: Optional[int] = None,
    progress: Progress = None,
    controls: Any = None,
    initial_state: Any = None,
    metrics_only: bool = False,
    executor: object = None,
    chunk_size: Optional[int] = None,
    policy: Optional[Policy] = None,
    control_every: int = 1,
    audit_energy: bool = False,
) -> BatchTable[ScenarioResult]:
    """Runs a scenario once per (seed, timestep) pair, in parallel over one
    scene, and returns a simloop.BatchTable: one row per run.

    Runs come in the order of itertools.product(seeds, timesteps), and each
    is bitwise identical to run_scenario() with the same arguments, whatever
    `threads` is (None: one worker per core). A timestep of None is the
    scenario's own (or the scene's). The scene is compiled once per distinct
    timestep and shared; each worker steps its own MuJoCo data. Every run is
    checked before any starts, and so is the memory all the kept trajectories
    take together. progress: as for run(), over the steps of all the runs.

    The table is the same in every mode (the same columns, order and dtypes,
    the same bits): `run` (the row's index in the batch), the parameters,
    each recorded body's final position and speed, the disturbances as
    drawn, warning counts and diverged, unrounded. Run locally without
    metrics_only, the batch also keeps each run's ScenarioResult (trajectory
    and all) as table.results, in the rows' order.

    controls: (runs, steps, nu), run i following controls[i], or (steps, nu)
    for every run; initial_state: (runs, state_size) or (state_size,). As
    for run_scenario(), and read in place. runs is len(seeds) *
    len(timesteps), in the rows' order.
    metrics_only: keep no trajectories (and no results: table.results
    raises ValueError), so that memory does not grow with the runs' lengths.

    executor: a dask.distributed Client or a concurrent.futures.Executor, as
    for run_batch(): chunks on workers, metrics only, no results back (the
    scenario travels as its TOML text; model must be None; controls and
    initial_state go with the chunks, each chunk its runs' rows of a
    per-run array; a policy goes with each chunk, pickled (cloudpickle for
    Dask, pickle for a process pool: one that is not is refused, naming it),
    its table's bits the local batch's).

    policy, control_every: as for run_scenario(); one policy for every run,
    called with the GIL held from whichever worker reaches a decision (the
    others step on meanwhile). Results stay bitwise those of run_scenario()
    whatever `threads` is, as long as the policy's answer depends only on
    the observation it is given.

    audit_energy: as for run_scenario(), each run's result (not the table's
    metrics, which it does not change); not with an executor.
    """
    audit = _check_bool("audit_energy", audit_energy)
    if executor is not None:
        if audit:
            raise ValueError("audit_energy is not sent to an executor: its batches keep metrics only")
        if model is not None:
            raise TypeError("model must be None with executor= (the scenario's scene is compiled on each worker)")
    scenario, scene = _scenario_and_scene(scenario, model)  # with executor=, compiled here too: see below
    seed_list = [_check_seed("seeds[%d]" % i, s) for i, s in enumerate(_sequence("seeds", seeds))]
    timestep_list = [
        None if t is None else _check_real("timesteps[%d]" % i, t)
        for i, t in enumerate(_sequence("timesteps", timesteps))
    ]
    workers = _check_threads(threads)
    rng, step_count = _check_str("rng", rng), None if steps is None else _check_int("steps", steps)
    perturb, every = _check_bool("perturb", perturb), _check_int("record_every", record_every)
    if executor is not None:
        from .distributed import run_scenario_batch_on  # numpy: `import simloop` does not load it

        # What the C++ side checks of a run (names, rng, timestep, length),
        # here, once per timestep, before any work goes out.
        for t in dict.fromkeys(timestep_list):
            _core.check_scenario(scene, scenario._core, _core.ScenarioConfig(0, rng, t, step_count, perturb, every))
        if policy is None:
            _check_no_control_every(control_every)
        elif controls is not None or initial_state is not None:
            raise ValueError(_POLICY_ALONE)
        own, start = _batch_inputs(controls, initial_state)
        _core.check_batch_inputs(len(seed_list) * len(timestep_list), own, start)  # their values: on the workers
        return run_scenario_batch_on(
            executor,
            scenario,
            seed_list,
            timestep_list,
            rng=rng,
            steps=step_count,
            perturb=perturb,
            threads=threads,
            chunk_size=chunk_size,
            progress=_check_progress(progress),
            inputs={"controls": own, "initial_state": start},
            policy=policy,
            control_every=control_every,
        )
    configs = [
        _core.ScenarioConfig(s, rng, t, step_count, perturb, every, audit) for s in seed_list for t in timestep_list
    ]
    metrics_only = _check_bool("metrics_only", metrics_only)
    from .tables import _core_table, _table  # numpy: `import simloop` does not load it

    if policy is not None:
        if controls is not None or initial_state is not None or metrics_only:
            raise ValueError(_POLICY_ALONE)
        if not configs:
            return _table([], keep_results=True)
        decide, decide_every = _decider(policy, control_every, scene, scenario, configs[0])
        return _table(
            _core.run_scenario_batch(
                scene,
                scenario._core,
                configs,
                workers,
                decide=decide,
                control_every=decide_every,
                progress=_check_progress(progress),
            ),
            keep_results=True,
        )
    _check_no_control_every(control_every)
    own, start = _batch_inputs(controls, initial_state)
    if metrics_only:  # each run reduced to its row as it ends: no per-run result, in C++ or Python
        return _core_table(
            _core.run_scenario_table(
                scene, scenario._core, configs, workers, own, start, progress=_check_progress(progress)
            )
        )
    results = _core.run_scenario_batch(
        scene, scenario._core, configs, workers, controls=own, initial_state=start, progress=_check_progress(progress)
    )
    return _table(results, keep_results=True)
