"""MJCF of the UR3 (bodies placed from the DH table) and the two-finger parallel gripper.

Each DH row becomes a body at (a, 0, d) rotated by Rx(alpha) in its parent, with a hinge about
its own z, so MuJoCo's qpos equals the DH joint vector of `ur3_kinematics`. Arm links are
visual-only capsules (no self- or world-collision): only the gripper touches the world.
"""

from __future__ import annotations

import numpy as np

from sortbot.config import GripperConfig
from sortbot.sim import ur3_kinematics as kin

ARM_JOINTS = kin.JOINT_NAMES
FINGER_JOINTS = ("finger_left", "finger_right")
FINGER_PAD_GEOMS = ("pad_left", "pad_right")
TCP_SITE = "tcp"

# Link masses (kg) from the UR3 URDF; visual radii (m).
_LINK_MASS = (2.0, 3.42, 1.26, 0.8, 0.8, 0.35)
_LINK_RADIUS = (0.045, 0.040, 0.032, 0.030, 0.030, 0.032)
# Servo gains per joint: stiff enough to track within a few mrad with gravity compensated.
_KP = (4000.0, 4000.0, 2500.0, 800.0, 800.0, 500.0)
_KV = (120.0, 120.0, 60.0, 15.0, 15.0, 8.0)


def _quat_rx(alpha: float) -> str:
    return f"{np.cos(alpha / 2):.9f} {np.sin(alpha / 2):.9f} 0 0"


def _link_geom(i: int) -> str:
    """Capsule along the link's DH offset (visual only)."""
    r, m = _LINK_RADIUS[i], _LINK_MASS[i]
    if i in (1, 2):  # upper arm and forearm run along x by a
        to = f"{kin.A[i]:.5f} 0 0"
    elif i == 0:
        to = f"0 0 {kin.D[0]:.5f}"
        return f'<geom class="arm" type="cylinder" fromto="0 0 0 {to}" size="{r}" mass="{m}"/>'
    else:
        to = f"0 0 {kin.D[i]:.5f}"
    return f'<geom class="arm" type="capsule" fromto="0 0 0 {to}" size="{r}" mass="{m}"/>'


def gripper_xml(cfg: GripperConfig) -> str:
    """Palm and two fingers sliding along the flange x axis (the closing axis).

    The finger joint is the inward travel of each pad (0 = open by `stroke`). Contact parameters
    on the pads (stiff solref, hard solimp, condim 4 with torsional friction, friction 1.5) are what
    keep a 3 mm knife from squeezing out sideways or rotating about the grasp axis.
    """
    half_open = cfg.stroke / 2
    pad_half = cfg.pad_thickness / 2
    finger_z = cfg.tool_length - cfg.finger_length / 2
    palm_z = cfg.tool_length - cfg.finger_length - 0.015
    fingers = []
    for side, sign in (("left", -1.0), ("right", 1.0)):
        x0 = sign * (half_open + pad_half)
        fingers.append(
            f"""
      <body name="finger_{side}" pos="{x0:.5f} 0 0">
        <joint name="finger_{side}" type="slide" axis="{-sign:.0f} 0 0" range="0 {half_open:.5f}"
               armature="0.01" damping="2"/>
        <geom name="pad_{side}" class="pad" type="box" pos="0 0 {finger_z:.5f}"
              size="{pad_half:.5f} {cfg.finger_width / 2:.5f} {cfg.finger_length / 2:.5f}" mass="0.05"/>
        <geom class="gripper_visual" type="box" pos="{sign * 0.006:.4f} 0 {palm_z + 0.008:.5f}"
              size="0.006 {cfg.finger_width / 2:.5f} 0.008" mass="0.02"/>
      </body>"""
        )
    return f"""
    <body name="gripper" pos="0 0 0">
      <geom class="gripper_visual" type="cylinder" pos="0 0 0.01" size="0.032 0.01" mass="0.1"/>
      <geom name="palm" class="gripper_collision" type="box" pos="0 0 {palm_z:.5f}"
            size="{half_open + 0.012:.5f} 0.022 0.012" mass="0.5"/>
      <site name="{TCP_SITE}" pos="0 0 {cfg.tool_length:.5f}" size="0.003" rgba="1 0 0 0"/>
      {''.join(fingers)}
    </body>"""


def arm_xml(cfg: GripperConfig) -> str:
    """Nested bodies base -> flange -> gripper."""
    bodies_open, bodies_close = [], []
    pos, quat = "0 0 0", "1 0 0 0"
    for i, name in enumerate(ARM_JOINTS):
        rng = f"{kin.JOINT_LOWER[i]:.5f} {kin.JOINT_UPPER[i]:.5f}"
        bodies_open.append(
            f"""
  <body name="link{i + 1}" pos="{pos}" quat="{quat}" gravcomp="1">
    <joint name="{name}" axis="0 0 1" range="{rng}" armature="0.1" damping="1"/>
    {_link_geom(i)}"""
        )
        bodies_close.append("</body>")
        pos = f"{kin.A[i]:.6f} 0 {kin.D[i]:.6f}"
        quat = _quat_rx(kin.ALPHA[i])
    flange = f'<body name="flange" pos="{pos}" quat="{quat}" gravcomp="1">{gripper_xml(cfg)}</body>'
    base = '<geom class="arm" type="cylinder" pos="0 0 0.02" size="0.064 0.02" mass="1"/>'
    return base + "".join(bodies_open) + flange + "".join(reversed(bodies_close))


def actuators_xml(cfg: GripperConfig) -> str:
    arm = []
    for i, name in enumerate(ARM_JOINTS):
        torque = kin.JOINT_MAX_TORQUE[i] * 3  # peak torque is ~3x rated on UR joints
        arm.append(
            f'<position name="{name}" joint="{name}" kp="{_KP[i]}" kv="{_KV[i]}" '
            f'forcerange="{-torque} {torque}" ctrlrange="{kin.JOINT_LOWER[i]:.5f} {kin.JOINT_UPPER[i]:.5f}"/>'
        )
    # Finger servo: kp so that the rated force is reached about 2 cm short of the target; the
    # force range caps the squeeze at the RG2's rated force.
    kp = cfg.max_force / 0.02
    fingers = [
        f'<position name="{j}" joint="{j}" kp="{kp:.1f}" kv="20" forcerange="{-cfg.max_force} {cfg.max_force}" '
        f'ctrlrange="0 {cfg.stroke / 2:.5f}"/>'
        for j in FINGER_JOINTS
    ]
    return "<actuator>" + "".join(arm + fingers) + "</actuator>"


def defaults_xml(cfg: GripperConfig) -> str:
    return f"""
    <default class="arm">
      <geom contype="0" conaffinity="0" group="1" rgba="0.55 0.6 0.68 1"/>
    </default>
    <default class="gripper_visual">
      <geom contype="0" conaffinity="0" group="1" rgba="0.15 0.15 0.17 1"/>
    </default>
    <default class="gripper_collision">
      <geom contype="1" conaffinity="1" group="1" rgba="0.15 0.15 0.17 1" friction="0.8 0.02 0.001"/>
    </default>
    <default class="pad">
      <!-- stiff, hard contacts with torsional friction: the pads must hold a 3 mm knife edge -->
      <geom contype="1" conaffinity="1" group="1" rgba="0.25 0.25 0.28 1" condim="4"
            friction="{cfg.pad_friction} 0.02 0.001" solref="0.004 1" solimp="0.95 0.99 0.001" priority="1"/>
    </default>"""
