"""Every tunable number of the simulated world, named, in dataclasses (DESIGN section 3).

Defaults describe the reference scene: a UR3 on a table, a pick area in front of it, three bins
beside it, an RGB-D camera in front looking back at the pick area.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class PhysicsConfig:
    timestep: float = 0.002
    # Thin cutlery held by friction needs elliptic cones, a high impratio and noslip passes,
    # otherwise the knife creeps out of the fingers while lifting (DESIGN section 5).
    cone: str = "elliptic"
    impratio: float = 10.0
    noslip_iterations: int = 3  # applied only while the fingers squeeze something (halves the step rate)
    solver_iterations: int = 50
    table_friction: float = 0.6
    object_friction: float = 0.8
    max_object_speed: float = 20.0  # m/s: faster than this is a blow-up, not physics


@dataclass
class GripperConfig:
    """Two-finger parallel jaw, RG2-like."""

    stroke: float = 0.100  # fully open distance between pads
    tool_length: float = 0.130  # flange to the fingertip centre (the TCP)
    finger_length: float = 0.050
    finger_width: float = 0.020  # along the object (perpendicular to the closing axis)
    pad_thickness: float = 0.006
    pad_friction: float = 1.5
    max_force: float = 40.0  # N, RG2's rated grip force
    close_speed: float = 0.10  # m/s per finger; instant closing lets the pads ride over a knife
    grasp_opening: float = 0.045  # pre-shape before descending: wide enough for a spoon bowl, short to close
    fingertip_clearance: float = 0.001  # fingertips this far above the table when grasping flat objects


@dataclass
class MotionConfig:
    """Speed and acceleration limits for every primitive (a jump in target jerks a knife out)."""

    joint_speed: float = 3.0  # rad/s in free space (UR3 limit: 3.14 big joints, 6.28 wrists)
    joint_accel: float = 15.0  # rad/s^2
    approach_height: float = 0.06  # above the target before descending
    cartesian_speed: float = 0.5  # m/s for descents, pushes and lifts
    cartesian_accel: float = 4.0  # m/s^2
    lift_speed: float = 0.3  # m/s while holding an object
    lift_height: float = 0.09  # TCP height above the table after a grasp
    push_length: float = 0.10
    push_height: float = 0.0015  # fingertips above the table while pushing: below a 2 mm blade
    place_height: float = 0.10  # TCP height above the table when releasing into a bin
    settle_time: float = 0.15  # s of physics after releasing or pushing before measuring
    servo_tolerance: float = 0.02  # rad: joints must reach their target this close
    servo_timeout: float = 0.6  # s allowed to converge after a trajectory ends
    home_tcp: tuple[float, float, float] = (0.12, 0.0, 0.33)  # above the robot, out of the camera's view
    home_yaw: float = 0.0


@dataclass
class CameraConfig:
    width: int = 640
    height: int = 480
    focal_length: float = 618.62  # px, as the paper's camera
    position: tuple[float, float, float] = (0.74, 0.0, 0.55)
    lookat: tuple[float, float, float] = (0.30, 0.0, 0.0)
    near: float = 0.01
    far: float = 10.0


@dataclass
class WorkspaceConfig:
    """Pick area and bins in the base frame (metres)."""

    pick_min: tuple[float, float] = (0.17, -0.14)
    pick_max: tuple[float, float] = (0.43, 0.14)
    table_height: float = 0.0  # the robot is mounted on the table top
    drop_margin: float = 0.05  # random drops land this far inside the pick area
    drop_height: tuple[float, float] = (0.03, 0.12)
    # bins: class -> (centre x, centre y, yaw of the long side)
    bins: dict[str, tuple[float, float, float]] = field(
        default_factory=lambda: {
            "fork": (0.0, 0.29, 0.0),
            "knife": (-0.29, 0.0, np.pi / 2),
            "spoon": (0.0, -0.29, 0.0),
        }
    )
    bin_inner_size: tuple[float, float] = (0.26, 0.11)  # long side, short side
    bin_wall_height: float = 0.04
    bin_wall_thickness: float = 0.006
    source_container: bool = False  # a shallow tray around the pick area
    container_wall_height: float = 0.03


@dataclass
class ObjectConfig:
    """Procedural object dimensions, sampled uniformly from these ranges (metres)."""

    fork_length: tuple[float, float] = (0.15, 0.19)
    knife_length: tuple[float, float] = (0.17, 0.21)
    spoon_length: tuple[float, float] = (0.14, 0.18)
    handle_width: tuple[float, float] = (0.012, 0.018)
    handle_thickness: tuple[float, float] = (0.003, 0.005)
    head_thickness: tuple[float, float] = (0.002, 0.003)
    fork_head_width: tuple[float, float] = (0.020, 0.026)
    fork_tines: tuple[int, int] = (3, 4)
    knife_blade_width: tuple[float, float] = (0.016, 0.022)
    spoon_bowl_width: tuple[float, float] = (0.030, 0.042)
    spoon_bowl_length: tuple[float, float] = (0.045, 0.060)
    block_size: tuple[float, float] = (0.020, 0.035)
    density: float = 7800.0  # stainless steel
    block_density: float = 1000.0
    mesh_files: tuple[str, ...] = ()  # user meshes (OBJ/STL) for the "mesh" object set
    mesh_classes: tuple[str, ...] = ()  # class of each mesh file
    mesh_scale: float = 1.0


@dataclass
class OutcomeConfig:
    push_moved_distance: float = 0.01  # m: an object moved at least this far...
    push_moved_angle: float = float(np.deg2rad(10.0))  # ...or turned at least this much
    held_lift: float = 0.04  # m above its resting height for an object to count as held
    held_radius: float = 0.12  # m: a held object stays within this of the TCP
    # VPG's change detector: depth changes between 1 cm and 30 cm over more than ~300 heightmap
    # pixels of 2 mm (12 cm^2). Measured here in metric area so it does not depend on the image size.
    change_depth_min: float = 0.01
    change_depth_max: float = 0.30
    change_area: float = 0.0012  # m^2
    max_consecutive_failures: int = 10
    max_steps: int = 40
    reward_grasp: float = 1.0
    reward_well_placed: float = 1.0
    reward_push: float = 0.5


@dataclass
class SceneConfig:
    object_set: str = "cutlery"  # cutlery | blocks | mesh
    num_objects: int = 6
    settle_time: float = 1.0  # s of physics after dropping, before the first observation


@dataclass
class EnvConfig:
    physics: PhysicsConfig = field(default_factory=PhysicsConfig)
    gripper: GripperConfig = field(default_factory=GripperConfig)
    motion: MotionConfig = field(default_factory=MotionConfig)
    camera: CameraConfig = field(default_factory=CameraConfig)
    workspace: WorkspaceConfig = field(default_factory=WorkspaceConfig)
    objects: ObjectConfig = field(default_factory=ObjectConfig)
    outcome: OutcomeConfig = field(default_factory=OutcomeConfig)
    scene: SceneConfig = field(default_factory=SceneConfig)


@dataclass
class DatasetConfig:
    """How collected episodes are written (DESIGN section 4): LeRobot v3 dataset + MCAP logs."""

    fps: int = 5  # nominal decision rate stored in the dataset (one frame per decision)
    max_objects: int = 10  # rows of `observation.labels`; the largest scene has 10 objects
    # Depth goes into lerobot's 12-bit depth-map video. A linear 0.1-1.5 m range gives 0.34 mm
    # quanta, finer than the 3 mm knife blade (lerobot's default log range 0.01-10 m gives ~1.4 mm).
    depth_min: float = 0.1
    depth_max: float = 1.5
    depth_use_log: bool = False
    rgb_crf: int = 23  # libsvtav1 quality for the RGB video (lower = better, larger)
    # episodes staged (each its own small dataset) before they are folded into the dataset with
    # lerobot's aggregation: a fold copies the whole dataset, so larger is cheaper for long runs
    fold_every: int = 50
    encode_attempts: int = 3  # lerobot's HEVC depth encoding fails intermittently (PyAV PatchWelcomeError)
    mcap_image_format: str = "png"  # /camera/rgb CompressedImage format: png (lossless) or jpeg
    mcap_jpeg_quality: int = 90
