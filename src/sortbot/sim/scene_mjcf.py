"""Assemble the world MJCF: table, pick area, bins, optional source tray, camera, UR3, objects."""

from __future__ import annotations

import numpy as np

from sortbot.config import EnvConfig
from sortbot.sim import objects as obj
from sortbot.sim import robot_mjcf

CAMERA_NAME = "rgbd"


def object_body_name(index: int) -> str:
    return f"object{index:02d}"


def camera_axes(position: np.ndarray, lookat: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Right, up and forward unit vectors of a camera at `position` looking at `lookat`."""
    forward = np.asarray(lookat, float) - np.asarray(position, float)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, (0.0, 0.0, 1.0))
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    return right, up, forward


def fovy_degrees(focal_length: float, height: int) -> float:
    return float(np.rad2deg(2 * np.arctan(height / 2 / focal_length)))


def _bin_xml(name: str, centre: tuple[float, float, float], cfg: EnvConfig) -> str:
    ws = cfg.workspace
    x, y, yaw = centre
    long_half, short_half = ws.bin_inner_size[0] / 2, ws.bin_inner_size[1] / 2
    t, h = ws.bin_wall_thickness / 2, ws.bin_wall_height / 2
    walls = [
        ((0, 0, t), (long_half + 2 * t, short_half + 2 * t, t)),  # floor
        ((0, short_half + t, h), (long_half + 2 * t, t, h)),
        ((0, -short_half - t, h), (long_half + 2 * t, t, h)),
        ((long_half + t, 0, h), (t, short_half, h)),
        ((-long_half - t, 0, h), (t, short_half, h)),
    ]
    geoms = "".join(
        f'<geom class="bin" type="box" pos="{p[0]:.4f} {p[1]:.4f} {p[2]:.4f}" size="{s[0]:.4f} {s[1]:.4f} {s[2]:.4f}"/>'
        for p, s in walls
    )
    return f'<body name="bin_{name}" pos="{x} {y} 0" euler="0 0 {yaw}">{geoms}</body>'


def _container_xml(cfg: EnvConfig) -> str:
    ws = cfg.workspace
    (x0, y0), (x1, y1) = ws.pick_min, ws.pick_max
    cx, cy, hx, hy = (x0 + x1) / 2, (y0 + y1) / 2, (x1 - x0) / 2, (y1 - y0) / 2
    h, t = ws.container_wall_height / 2, 0.004
    walls = [((cx, y1 + t, h), (hx + 2 * t, t, h)), ((cx, y0 - t, h), (hx + 2 * t, t, h)),
             ((x1 + t, cy, h), (t, hy, h)), ((x0 - t, cy, h), (t, hy, h))]
    return "".join(
        f'<geom class="bin" type="box" pos="{p[0]:.4f} {p[1]:.4f} {p[2]:.4f}" size="{s[0]:.4f} {s[1]:.4f} {s[2]:.4f}"/>'
        for p, s in walls
    )


def world_xml(cfg: EnvConfig, specs: list[obj.ObjectSpec]) -> str:
    ph, cam, ws = cfg.physics, cfg.camera, cfg.workspace
    right, up, _ = camera_axes(np.array(cam.position), np.array(cam.lookat))
    xyaxes = " ".join(f"{v:.6f}" for v in (*right, *up))
    (x0, y0), (x1, y1) = ws.pick_min, ws.pick_max
    names = [object_body_name(i + 1) for i in range(len(specs))]
    assets = "".join(obj.asset_xml(s, n) for s, n in zip(specs, names))
    bodies = "".join(obj.body_xml(s, n) for s, n in zip(specs, names))
    bins = "".join(_bin_xml(cls, centre, cfg) for cls, centre in ws.bins.items())
    container = _container_xml(cfg) if ws.source_container else ""
    return f"""
<mujoco model="sortbot">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{ph.timestep}" integrator="implicitfast" cone="{ph.cone}" impratio="{ph.impratio}"
          noslip_iterations="{ph.noslip_iterations}" iterations="{ph.solver_iterations}">
    <!-- no silent auto-reset on bad accelerations: the env detects the blow-up and ends the episode -->
    <flag autoreset="disable"/>
  </option>
  <visual>
    <!-- no shadows, no multisampling: on software GL they cost ~6x the render time -->
    <quality offsamples="0" shadowsize="0"/>
    <global offwidth="{cam.width}" offheight="{cam.height}"/>
    <map znear="{cam.near}" zfar="{cam.far}"/>
    <headlight ambient="0.35 0.35 0.35" diffuse="0.45 0.45 0.45" specular="0.2 0.2 0.2"/>
  </visual>
  <default>
    {robot_mjcf.defaults_xml(cfg.gripper)}
    {obj.defaults_xml(cfg.objects, ph.object_friction)}
    <default class="bin"><geom contype="1" conaffinity="1" group="0" rgba="0.45 0.47 0.5 1" friction="0.6 0.01 0.001"/></default>
  </default>
  <asset>
    <texture name="wood" type="2d" builtin="flat" rgb1="0.62 0.5 0.38" width="8" height="8"/>
    <material name="table" texture="wood" rgba="1 1 1 1" specular="0.1"/>
    <material name="metal" rgba="0.78 0.79 0.82 1" specular="0.9" shininess="0.9"/>
    <material name="pick" rgba="0.32 0.32 0.34 1" specular="0.05"/>
    {assets}
  </asset>
  <worldbody>
    <light name="top" pos="0.3 0 1.5" dir="0 0 -1" directional="true" diffuse="0.5 0.5 0.5" specular="0.3 0.3 0.3" castshadow="false"/>
    <geom name="table" type="plane" size="0.6 0.6 0.01" pos="0 0 {ws.table_height}" material="table"
          friction="{ph.table_friction} 0.01 0.001" group="0"/>
    <geom name="pick_area" type="box" contype="0" conaffinity="0" group="0" material="pick"
          pos="{(x0 + x1) / 2} {(y0 + y1) / 2} {ws.table_height - 0.0005}" size="{(x1 - x0) / 2} {(y1 - y0) / 2} 0.0004"/>
    {container}
    {bins}
    <camera name="{CAMERA_NAME}" pos="{" ".join(map(str, cam.position))}" xyaxes="{xyaxes}"
            fovy="{fovy_degrees(cam.focal_length, cam.height):.6f}"/>
    {robot_mjcf.arm_xml(cfg.gripper)}
    {bodies}
  </worldbody>
  {robot_mjcf.actuators_xml(cfg.gripper)}
</mujoco>"""
