import numpy as np
import pytest

from conftest import single_object_scene
from sortbot.config import CameraConfig, WorkspaceConfig
from sortbot.perception import HeightmapConfig, make_heightmap, observation_heightmap
from sortbot.sim.env import SortingEnv
from sortbot.sim.objects import ObjectSpec
from sortbot.types import CameraIntrinsics, CameraPose


def _camera(cfg=CameraConfig()):
    """The reference camera: OpenCV axes (x right, y down, z forward) looking at cfg.lookat."""
    pos, at = np.array(cfg.position), np.array(cfg.lookat)
    forward = (at - pos) / np.linalg.norm(at - pos)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    pose = CameraPose(position=pos, rotation=np.stack([right, down, forward], axis=1))
    f = cfg.focal_length
    intr = CameraIntrinsics(fx=f, fy=f, cx=cfg.width / 2, cy=cfg.height / 2, width=cfg.width, height=cfg.height)
    return intr, pose


def _depth_of_box_on_table(intr, pose, lo, hi):
    """Ray-cast a table (z = 0) with an axis-aligned box [lo, hi] on it: depth along the optical axis."""
    v, u = np.mgrid[0:intr.height, 0:intr.width].astype(float)
    rays_cam = np.stack([(u - intr.cx) / intr.fx, (v - intr.cy) / intr.fy, np.ones_like(u)], axis=-1)  # z = 1
    rays = rays_cam @ pose.rotation.T
    o = pose.position
    t_table = -o[2] / rays[..., 2]
    with np.errstate(divide="ignore"):
        t1 = (np.asarray(lo) - o) / rays
        t2 = (np.asarray(hi) - o) / rays
    t_near = np.minimum(t1, t2).max(axis=-1)
    t_far = np.maximum(t1, t2).min(axis=-1)
    hit = (t_near <= t_far) & (t_near > 0)
    # t scales the ray whose optical-axis component is 1, so t is the depth itself
    return np.where(hit, t_near, t_table).astype(np.float32)


def test_box_has_its_height_in_its_footprint_and_the_table_is_zero():
    intr, pose = _camera()
    lo, hi = (0.28, 0.02, 0.0), (0.32, 0.06, 0.025)  # a 4 x 4 cm box, 2.5 cm tall
    depth = _depth_of_box_on_table(intr, pose, lo, hi)
    rgb = np.full((intr.height, intr.width, 3), 90, np.uint8)
    cfg = HeightmapConfig()
    hm = make_heightmap(rgb, depth, intr, pose, cfg)
    assert hm.depth.shape == cfg.shape == (140, 130) and hm.color.shape == (140, 130, 3)

    rows, cols = np.mgrid[0:cfg.shape[0], 0:cfg.shape[1]]
    x, y = cfg.pixel_to_base(rows, cols)
    m = cfg.resolution
    inside = (x > lo[0] + m) & (x < hi[0] - m) & (y > lo[1] + m) & (y < hi[1] - m)
    outside = (x < lo[0] - 2 * m) | (x > hi[0] + 2 * m) | (y < lo[1] - 2 * m) | (y > hi[1] + 2 * m)
    assert inside.sum() > 300
    assert np.allclose(hm.depth[inside], 0.025, atol=1e-4)
    # the table: everything seen is at height 0; cells hidden behind the box (from the camera) stay 0 too
    assert np.abs(hm.depth[outside]).max() < 1e-4
    assert hm.depth.max() == pytest.approx(0.025, abs=1e-4)
    # the camera sees the whole pick area except the box's shadow
    assert hm.valid[outside].mean() > 0.97 and hm.valid[inside].all()
    assert (hm.color[hm.valid] == 90).all() and (hm.color[~hm.valid] == 0).all()


def test_highest_point_wins_and_empty_cells_are_zero():
    """Three returns in one cell: the highest one's height and colour are kept, whatever their order."""
    intr, pose = _camera()
    depth = np.zeros((intr.height, intr.width), np.float32)  # no returns anywhere...
    rgb = np.zeros((intr.height, intr.width, 3), np.uint8)
    cfg = HeightmapConfig()
    centre = np.array(cfg.pixel_to_base(75, 65))
    for h, colour in ((0.010, 50), (0.020, 200), (0.015, 120)):  # ...but three at the same spot, stacked
        p_cam = (np.array([*centre, h]) - pose.position) @ pose.rotation
        u = int(round(p_cam[0] / p_cam[2] * intr.fx + intr.cx))
        v = int(round(p_cam[1] / p_cam[2] * intr.fy + intr.cy))
        ray = pose.rotation @ np.array([(u - intr.cx) / intr.fx, (v - intr.cy) / intr.fy, 1.0])
        depth[v, u] = (h - pose.position[2]) / ray[2]  # where this pixel's ray is at height h
        rgb[v, u] = colour
    assert np.count_nonzero(depth) == 3
    hm = make_heightmap(rgb, depth, intr, pose, cfg)
    assert hm.valid.sum() == 1 and hm.valid[75, 65]
    assert hm.depth[75, 65] == pytest.approx(0.020, abs=1e-5) and tuple(hm.color[75, 65]) == (200, 200, 200)
    assert np.count_nonzero(hm.depth) == 1 and np.count_nonzero(hm.color) == 3


def test_pixel_base_round_trip_and_grid_orientation():
    cfg = HeightmapConfig.from_workspace(WorkspaceConfig(), resolution=0.004)
    assert cfg.shape == (70, 65)
    rows, cols = np.mgrid[0:70, 0:65]
    x, y = cfg.pixel_to_base(rows, cols)
    r2, c2 = cfg.base_to_pixel(x, y)
    assert np.array_equal(r2, rows) and np.array_equal(c2, cols)
    # rows run along +y, columns along +x, from the pick area's minimum corner
    assert cfg.pixel_to_base(0, 0) == pytest.approx((0.17 + 0.002, -0.14 + 0.002))
    assert cfg.pixel_to_base(69, 0)[1] > cfg.pixel_to_base(0, 0)[1]
    assert cfg.pixel_to_base(0, 64)[0] > cfg.pixel_to_base(0, 0)[0]
    assert not cfg.contains(*cfg.base_to_pixel(0.5, 0.0)) and cfg.contains(*cfg.base_to_pixel(0.3, 0.0))
    with pytest.raises(ValueError, match="resolution"):
        HeightmapConfig(resolution=0.0)


def test_rendered_cube_stands_at_its_size(env: SortingEnv):
    cube = ObjectSpec(cls="block", shape="cube", params={"size": 0.03})
    obs = env.reset(scene=single_object_scene(cube, 0.33, -0.05, 0.0))
    hm = observation_heightmap(obs)
    cfg = hm.config
    r, c = cfg.base_to_pixel(0.33, -0.05)
    assert hm.depth[r - 3:r + 4, c - 3:c + 4] == pytest.approx(np.full((7, 7), 0.03), abs=1.5e-3)
    far = cfg.base_to_pixel(0.22, 0.08)
    assert abs(hm.depth[far]) < 1.5e-3 and hm.valid[far]
    # nothing but the cube rises above a few millimetres, and it covers its 3 x 3 cm footprint
    tall = hm.depth > 0.015
    assert 0.8 * (15 * 15) <= tall.sum() <= 1.2 * (15 * 15)
