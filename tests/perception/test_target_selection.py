import numpy as np
import pytest

from conftest import yaw_quat
from sortbot.perception import Detection, TargetConfig, candidate_targets, detections_from_labels, select_target
from sortbot.perception.pointcloud import object_cloud
from sortbot.sim.objects import sample_cutlery
from sortbot.sim.scene_file import SceneSpec

# three pieces apart on the table; the fork is nearest the robot base (at the origin)
LAYOUT = {"fork": (0.24, -0.05, 0.4), "knife": (0.37, 0.07, -0.3), "spoon": (0.34, -0.08, 1.3)}
CONFIDENCE = {"fork": 0.55, "knife": 0.9, "spoon": 0.8}


@pytest.fixture
def scene(env):
    rng = np.random.default_rng(3)
    objects = []
    for cls, (x, y, yaw) in LAYOUT.items():
        spec = sample_cutlery(cls, env.config.objects, rng)
        spec.position, spec.quaternion = (x, y, 0.001), yaw_quat(yaw)
        objects.append(spec)
    obs = env.reset(scene=SceneSpec(objects=objects, settle_time=0.3))
    labels = {l.cls: l for l in obs.labels}
    assert set(labels) == set(LAYOUT)
    dets = [Detection(box=tuple(map(float, labels[c].box)), confidence=CONFIDENCE[c], cls=c) for c in LAYOUT]
    return obs, labels, {s.cls: s for s in env.privileged_state()}, dets


def _pixel(obs, point):
    c = (point - obs.camera_pose.position) @ obs.camera_pose.rotation
    k = obs.intrinsics
    return int(round(c[1] / c[2] * k.fy + k.cy)), int(round(c[0] / c[2] * k.fx + k.cx))


def _on_object(obs, label, state, point):
    """The point is on the object: inside its mask (1 px tolerance) and its true outline, near its top."""
    v, u = _pixel(obs, point)
    in_mask = label.mask[v - 1:v + 2, u - 1:u + 2].any()
    p = state.spec.params
    local = point[:2] - state.position[:2]
    c, s = np.cos(state.long_axis_yaw), np.sin(state.long_axis_yaw)
    along, across = c * local[0] + s * local[1], -s * local[0] + c * local[1]
    half_w = max(p["handle_width"], p["head_width"]) / 2
    in_outline = abs(along) <= p["length"] / 2 + 0.002 and abs(across) <= half_w + 0.002
    return in_mask and in_outline and 0.0 < point[2] < 0.012


def test_nearest_object_is_chosen_and_the_target_lies_on_it(scene):
    obs, labels, states, dets = scene
    target = select_target(obs, dets)
    assert target.detection.cls == "fork" and target.detection.confidence == 0.55
    assert _on_object(obs, labels["fork"], states["fork"], target.point)
    assert target.distance == pytest.approx(np.linalg.norm(target.point[:2]))
    assert target.num_points > 100
    # every candidate lies on its own object, and the chosen one is nearest
    cands = candidate_targets(obs, dets)
    assert sorted(t.detection.cls for t in cands) == sorted(LAYOUT)
    for t in cands:
        assert _on_object(obs, labels[t.detection.cls], states[t.detection.cls], t.point), t.detection.cls
    assert target.distance == min(t.distance for t in cands)
    # the input order does not matter
    assert select_target(obs, dets[::-1]).detection == target.detection


def test_most_confident_detection_is_really_the_most_confident(scene):
    obs, labels, states, dets = scene
    # the paper's literal rule: the best score, wherever it sits in the list
    best = select_target(obs, dets, TargetConfig(selection="confidence"))
    assert best.detection.cls == "knife" and _on_object(obs, labels["knife"], states["knife"], best.point)
    assert [t.detection.confidence for t in candidate_targets(obs, dets)] == [0.9, 0.8, 0.55]
    # a less confident second guess for the fork, listed first, names the same object: the fork wins
    second_guess = Detection(box=dets[0].box, confidence=0.3, cls="spoon")
    chosen = select_target(obs, [second_guess, *dets])
    assert chosen.detection.cls == "fork" and chosen.detection.confidence == 0.55
    assert len(candidate_targets(obs, [second_guess, *dets])) == 3
    # below min_confidence a detection is ignored: the next nearest object is chosen
    weak_fork = [Detection(d.box, 0.1, d.cls) if d.cls == "fork" else d for d in dets]
    assert select_target(obs, weak_fork).detection.cls == "spoon"
    assert select_target(obs, [Detection(d.box, 0.1, d.cls) for d in dets]) is None


def test_object_cloud_is_the_object_in_the_base_frame(scene):
    obs, labels, states, _ = scene
    knife = labels["knife"]
    cloud = object_cloud(obs.depth, obs.intrinsics, obs.camera_pose, knife.box)
    assert len(cloud.points) > 100
    assert np.all(np.diff(cloud.points[:, 2]) <= 0)  # sorted by height, highest first
    assert cloud.points[:, 2].min() >= 0.001 and cloud.points[:, 2].max() < 0.012  # no table, no arm
    # all of it is the knife: within its outline (the box holds nothing else here)
    s = states["knife"]
    d = cloud.points[:, :2] - s.position[:2]
    along = np.abs(d @ [np.cos(s.long_axis_yaw), np.sin(s.long_axis_yaw)])
    assert along.max() <= s.spec.params["length"] / 2 + 0.003
    # the pixels recorded are where the points are seen
    v, u = cloud.pixels[:, 1].round().astype(int), cloud.pixels[:, 0].round().astype(int)
    assert knife.mask[v, u].mean() > 0.98


def test_ground_truth_detections_and_bad_settings():
    from sortbot.types import ObjectLabel

    label = ObjectLabel(1, "spoon", (10, 20, 30, 40), np.zeros((2, 2), bool), np.zeros(3), np.array([1.0, 0, 0, 0]))
    (det,) = detections_from_labels([label], confidence=0.7)
    assert det.as_array().tolist() == pytest.approx([10, 20, 30, 40, 0.7, 2])
    assert Detection.from_array(det.as_array()) == Detection((10.0, 20.0, 30.0, 40.0), pytest.approx(0.7), "spoon")
    with pytest.raises(ValueError, match="unknown class"):
        Detection((0, 0, 1, 1), 0.5, "plate")
    with pytest.raises(ValueError, match="selection"):
        TargetConfig(selection="farthest")


def test_empty_box_or_table_only_gives_no_target(scene):
    obs, *_ = scene
    assert select_target(obs, [Detection((600.0, 400.0, 630.0, 430.0), 0.9, "fork")]) is None  # bare table
    assert select_target(obs, []) is None
