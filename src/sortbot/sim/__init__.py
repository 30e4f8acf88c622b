"""The MuJoCo world: UR3 + gripper, table, bins, cutlery, RGB-D camera, primitives, SortingEnv.

Knows nothing of learning. The GL backend is chosen here, before anything imports mujoco.
"""

from sortbot.sim.gl_backend import select_backend

select_backend()
