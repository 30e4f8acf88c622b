"""Scenes as plain JSON/YAML files: object specs and poses that reproduce a layout exactly.

A random drop saved after settling has `settle_time: 0`: loading it puts every object exactly where
it rested, with zero velocity, so the first observation is identical. Hand-written hard cases give
approximate poses and a settle time.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np
import yaml

from sortbot.config import EnvConfig
from sortbot.sim.objects import CUTLERY_KINDS, ObjectSpec, sample_block, sample_cutlery, sample_mesh

SHIPPED_DIR = "scenes"


@dataclass
class SceneSpec:
    objects: list[ObjectSpec]
    settle_time: float = 0.0
    name: str = ""
    description: str = ""
    seed: int | None = None
    source_container: bool | None = None  # overrides WorkspaceConfig.source_container when set

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "description": self.description,
            "seed": self.seed,
            "settle_time": self.settle_time,
            "source_container": self.source_container,
            "objects": [o.to_dict() for o in self.objects],
        }

    @classmethod
    def from_dict(cls, data: dict) -> "SceneSpec":
        if not isinstance(data, dict) or not isinstance(data.get("objects"), list):
            raise ValueError("a scene file needs a top-level mapping with an 'objects' list")
        return cls(
            objects=[ObjectSpec.from_dict(o) for o in data["objects"]],
            settle_time=float(data.get("settle_time", 0.0)),
            name=str(data.get("name", "")),
            description=str(data.get("description", "")),
            seed=data.get("seed"),
            source_container=data.get("source_container"),
        )


def load_scene(path: str | Path) -> SceneSpec:
    """Read a scene file (JSON or YAML), or a shipped scene by name (see `shipped_scenes`)."""
    p = Path(path)
    if not p.exists() and str(path) in shipped_scenes():
        p = Path(str(resources.files("sortbot.sim") / SHIPPED_DIR / f"{path}.json"))
    if not p.is_file():
        raise FileNotFoundError(f"scene file {path} not found: give a JSON/YAML scene path or one of {', '.join(shipped_scenes())}")
    try:
        data = yaml.safe_load(p.read_text())  # YAML is a superset of JSON
        return SceneSpec.from_dict(data)
    except (yaml.YAMLError, KeyError, TypeError, ValueError) as err:
        raise ValueError(f"scene file {p} is not a valid scene ({err}); see sortbot/sim/scenes/*.json for the format") from None


def save_scene(scene: SceneSpec, path: str | Path) -> Path:
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    if p.suffix in (".yaml", ".yml"):
        p.write_text(yaml.safe_dump(scene.to_dict(), sort_keys=False))
    else:
        p.write_text(json.dumps(scene.to_dict(), indent=1))
    return p


def shipped_scenes() -> list[str]:
    folder = resources.files("sortbot.sim") / SHIPPED_DIR
    return sorted(Path(str(f)).stem for f in folder.iterdir() if str(f).endswith(".json"))


def _yaw_quat(yaw: float) -> tuple[float, float, float, float]:
    return (float(np.cos(yaw / 2)), 0.0, 0.0, float(np.sin(yaw / 2)))


def sample_scene(cfg: EnvConfig, seed: int) -> SceneSpec:
    """A random drop: objects above the pick area at staggered heights (so none start
    interpenetrating), random yaw, then `settle_time` of physics before the first observation."""
    rng = np.random.default_rng(seed)
    sc, ws = cfg.scene, cfg.workspace
    specs = []
    for i in range(sc.num_objects):
        if sc.object_set == "cutlery":
            spec = sample_cutlery(CUTLERY_KINDS[int(rng.integers(3))] if i >= 3 else CUTLERY_KINDS[i], cfg.objects, rng)
        elif sc.object_set == "blocks":
            spec = sample_block(cfg.objects, rng)
        elif sc.object_set == "mesh":
            spec = sample_mesh(cfg.objects, rng)
        else:
            raise ValueError(f"unknown object set {sc.object_set!r}: use cutlery, blocks or mesh")
        margin = ws.drop_margin
        x = rng.uniform(ws.pick_min[0] + margin, ws.pick_max[0] - margin)
        y = rng.uniform(ws.pick_min[1] + margin, ws.pick_max[1] - margin)
        z = ws.table_height + ws.drop_height[0] + (ws.drop_height[1] - ws.drop_height[0]) * i / max(1, sc.num_objects - 1)
        spec.position = (float(x), float(y), float(z))
        spec.quaternion = _yaw_quat(float(rng.uniform(-np.pi, np.pi)))
        specs.append(spec)
    # shuffle which object is which instance so classes are not ordered by height
    order = rng.permutation(len(specs))
    return SceneSpec(objects=[specs[k] for k in order], settle_time=sc.settle_time, name=f"random-{sc.object_set}-{sc.num_objects}", seed=seed)
