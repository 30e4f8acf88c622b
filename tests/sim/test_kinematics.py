import numpy as np
import pytest

from sortbot.config import EnvConfig
from sortbot.sim import ur3_kinematics as kin

YAWS = np.linspace(0, np.pi, 16, endpoint=False)


def test_inverse_recovers_random_configurations():
    rng = np.random.default_rng(0)
    for _ in range(300):
        q = rng.uniform(-np.pi, np.pi, 6)
        sols = kin.inverse(kin.forward(q))
        assert any(np.allclose(kin._wrap(s), kin._wrap(q), atol=1e-5) for s in sols)


def _reach_points():
    cfg = EnvConfig()
    ws, g = cfg.workspace, cfg.gripper
    pts = [(x, y, z) for x in np.linspace(ws.pick_min[0], ws.pick_max[0], 6)
           for y in np.linspace(ws.pick_min[1], ws.pick_max[1], 6) for z in (g.fingertip_clearance, cfg.motion.approach_height)]
    for bx, by, _ in ws.bins.values():
        pts.append((bx, by, cfg.motion.place_height))
    return pts, g.tool_length


def test_ik_reaches_pick_area_and_bins_at_16_yaws_in_one_posture_family():
    pts, tool = _reach_points()
    home = np.array([0.0, -np.pi / 2, -np.pi / 2, -np.pi / 2, np.pi / 2, 0.0])
    for p in pts:
        for yaw in YAWS:
            q = kin.solve_top_down(np.array(p), yaw, tool, home, symmetric=False)
            flange = kin.forward(q)
            tcp = flange[:3, 3] + tool * flange[:3, 2]
            assert np.allclose(tcp, p, atol=1e-6)
            assert np.allclose(flange[:3, 2], [0, 0, -1], atol=1e-6)  # tool points down
            assert abs(np.sin(kin.flange_yaw(q) - yaw)) < 1e-6 and np.cos(kin.flange_yaw(q) - yaw) > 0
            assert kin.is_preferred(q)


def test_unreachable_target_is_reported_not_clipped():
    with pytest.raises(kin.UnreachableError):
        kin.solve_top_down(np.array([0.9, 0.0, 0.0]), 0.0, 0.13, np.zeros(6))
