"""mujoco.batch.Batch as the third side of bench_rollout.py and bench_batch_anchor.py (both import it
from here, so neither imports the other)."""

import numpy as np

try:
    import mujoco
    import mujoco.batch
except ImportError:  # mujoco before 3.17, or none at all
    mujoco_batch = None
else:
    mujoco_batch = mujoco.batch


class BatchSide:
    """The same runs as mujoco.batch.Batch: the reset pose in its state rows, the same controls."""

    def __init__(self, inputs):
        self.inputs = inputs
        m = inputs.model
        self.full = mujoco.mjtState.mjSTATE_FULLPHYSICS
        integration = mujoco.mjtState.mjSTATE_INTEGRATION
        data = mujoco.MjData(m)
        mujoco.mj_resetData(m, data)
        row = np.empty(mujoco.mj_stateSize(m, integration))
        mujoco.mj_getState(m, data, row, integration)
        self.state0 = np.ascontiguousarray(np.tile(row, (inputs.batch, 1)))
        self.batches = {}

    def batch(self, threads):
        if threads not in self.batches:
            self.batches[threads] = mujoco_batch.Batch(self.inputs.model, self.inputs.batch, nthread=threads)
        return self.batches[threads]

    def check_start(self, rollout_state0):
        """The rows' time, qpos and qvel are rollout's initial state's."""
        b, m = self.batch(1), self.inputs.model
        b.state[:] = self.state0
        parts = ((b.time[:, None], 0, 1), (b.qpos, 1, 1 + m.nq), (b.qvel, 1 + m.nq, 1 + m.nq + m.nv))
        return all(np.array_equal(mine, rollout_state0[:, lo:hi]) for mine, lo, hi in parts)

    def run(self, threads, keep):
        b = self.batch(threads)
        b.state[:] = self.state0
        record = (self.full, "sensordata") if keep else ()
        return b.rollout(self.inputs.steps, self.inputs.controls, record=record)

    def qpos_qvel(self, threads, keep):
        """Final qpos and qvel of every run, from the recorded states or else the rows."""
        out, m = self.run(threads, keep), self.inputs.model
        if keep:
            last = out[self.full][:, -1, :]
            return last[:, 1 : 1 + m.nq].copy(), last[:, 1 + m.nq : 1 + m.nq + m.nv].copy()
        b = self.batch(threads)
        return b.qpos.copy(), b.qvel.copy()
