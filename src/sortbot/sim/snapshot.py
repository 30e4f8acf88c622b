"""Write one observation as files a person can open: RGB PNG, depth as 16-bit millimetre PNG,
segmentation as a colour PNG, labels as JSON."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from PIL import Image

from sortbot.types import Observation

_PALETTE = np.array([[0, 0, 0], [230, 25, 75], [60, 180, 75], [255, 225, 25], [0, 130, 200], [245, 130, 48],
                     [145, 30, 180], [70, 240, 240], [240, 50, 230], [210, 245, 60], [250, 190, 212], [0, 128, 128]], np.uint8)


def colour_instances(instances: np.ndarray) -> np.ndarray:
    return _PALETTE[np.where(instances > 0, (instances - 1) % (len(_PALETTE) - 1) + 1, 0)]


def write_snapshot(obs: Observation, instances: np.ndarray, out: Path) -> list[Path]:
    out = Path(out)
    paths = [out / "rgb.png", out / "depth.png", out / "segmentation.png", out / "labels.json"]
    Image.fromarray(obs.rgb).save(paths[0])
    depth_mm = np.clip(np.nan_to_num(obs.depth) * 1000.0, 0, 65535).astype(np.uint16)
    Image.fromarray(depth_mm).save(paths[1])
    Image.fromarray(colour_instances(instances)).save(paths[2])
    labels = [
        {"instance_id": l.instance_id, "class": l.cls, "box_xyxy": list(l.box), "pixels": int(l.mask.sum()),
         "position": [float(v) for v in l.position], "quaternion_wxyz": [float(v) for v in l.quaternion]}
        for l in obs.labels
    ]
    meta = {"intrinsics": vars(obs.intrinsics), "camera_pose_opencv": obs.camera_pose.matrix().tolist(),
            "depth_png": "uint16 millimetres", "labels": labels}
    paths[3].write_text(json.dumps(meta, indent=1))
    return paths
