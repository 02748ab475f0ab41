"""The chapter's loop as the chapter prints it (Python, numpy's generator, no
rerun), for measuring what it gives on another MuJoCo build: the fourth column
of the README's "chapter's figures beside ours" table.

Not part of simloop and not run by the tests. It needs the PyPI `mujoco`
package (and numpy), best in a scratch virtual environment:

    python3 -m venv /tmp/mj && /tmp/mj/bin/pip install mujoco==3.5.0 numpy
    /tmp/mj/bin/python bench/chapter_loop_reference.py --seed 0
    /tmp/mj/bin/python bench/chapter_loop_reference.py --timestep 0.05 --no-perturb

It prints one JSON line: the MuJoCo version, the shove, the chapter's
lateral_drift and final position, the peak box z over every step and over the
steps the chapter's recording logs (every 5th), and the largest |y|.
"""

import argparse
import json

import mujoco
import numpy as np

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--seed", type=int, default=0)
parser.add_argument("--steps", type=int, default=2000)
parser.add_argument("--timestep", type=float, default=0.002)
parser.add_argument("--no-perturb", dest="perturb", action="store_false")
args = parser.parse_args()
num_steps = args.steps
rng = np.random.default_rng(args.seed)
SCENE_XML = """
<mujoco model="pusher_scene">
  <worldbody>
    <light pos="0 0 3" dir="0 0 -1"/>
    <geom name="floor" type="plane" size="2 2 0.1" rgba="0.85 0.85 0.85 1"/>
    <body name="box" pos="0.4 0 0.05">
      <freejoint/>
      <geom name="box_geom" type="box" size="0.05 0.05 0.05" mass="0.5" rgba="0.85 0.3 0.25 1"/>
    </body>
    <body name="pusher" pos="0 0 0.05">
      <joint name="pusher_slide" type="slide" axis="1 0 0" damping="4"/>
      <geom name="pusher_geom" type="box" size="0.04 0.12 0.05" mass="1.0" rgba="0.25 0.45 0.85 1"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="push_motor" joint="pusher_slide" gear="10" ctrlrange="-1 1"/>
  </actuator>
</mujoco>
"""
model = mujoco.MjModel.from_xml_string(SCENE_XML)
model.opt.timestep = args.timestep
data = mujoco.MjData(model)
box = model.body("box")
push_start = num_steps // 2
push_steps = 50
push_newtons = rng.uniform(6.0, 12.0)
push_sign = rng.choice([-1.0, 1.0])
push_force = np.array([0.0, push_sign * push_newtons, 0.0])
mujoco.mj_forward(model, data)
zs, logged_z, ys = [], [], []  # box z every step, z as the chapter logs it, box y
for step in range(num_steps):
    in_shove = args.perturb and push_start <= step < push_start + push_steps
    if step == push_start:
        box_pos_at_push = data.xpos[box.id].copy()
    if step % 5 == 0:
        logged_z.append(float(data.xpos[box.id][2]))  # what the chapter's recording holds
    zs.append(float(data.qpos[2]))
    ys.append(float(data.qpos[1]))
    data.ctrl[0] = 1.0
    data.xfrc_applied[box.id, :3] = push_force if in_shove else 0.0
    mujoco.mj_step(model, data)
final_box_pos = data.qpos[0:3]
lateral_drift = float(abs(final_box_pos[1] - box_pos_at_push[1]))
print(
    json.dumps(
        {
            "mujoco": mujoco.__version__,
            "seed": args.seed,
            "timestep": args.timestep,
            "perturb": args.perturb,
            "shove_y": float(push_force[1]),
            "lateral_drift": round(lateral_drift, 6),
            "final_pos": [round(float(v), 6) for v in final_box_pos],
            "peak_z_every_step": round(max(zs + [float(data.qpos[2])]), 6),
            "peak_z_logged_every_5th": round(max(logged_z), 6),
            "max_abs_y": round(max(abs(v) for v in ys), 6),
        }
    )
)
