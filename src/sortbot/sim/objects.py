"""Objects to sort: procedural fork / knife / spoon, VPG-style blocks, user meshes (OBJ/STL).

An `ObjectSpec` is the complete, serialisable description of one object (shape parameters and
pose), so a scene file reproduces it exactly. Cutlery is built of primitive geoms in a local frame
with x along the length (handle at -x, head at +x), z up and the origin at the bottom centre, so a
flat object rests at z = 0. Fine detail (tines) is visual only; collision uses a plate under it.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from sortbot.config import ObjectConfig

CUTLERY_KINDS = ("fork", "knife", "spoon")
BLOCK_SHAPES = ("cube", "bar", "cylinder", "prism")
_METAL = ("0.78 0.79 0.82 1", "0.70 0.71 0.74 1", "0.82 0.80 0.76 1")
_BLOCK_COLOURS = ("0.31 0.48 0.65 1", "0.35 0.63 0.33 1", "0.93 0.56 0.17 1", "0.85 0.26 0.26 1", "0.94 0.80 0.25 1", "0.64 0.46 0.70 1")


@dataclass
class ObjectSpec:
    """One object: what it is, its shape parameters, and its pose (base frame, quat w x y z)."""

    cls: str  # fork | knife | spoon | block
    shape: str  # fork | knife | spoon | cube | bar | cylinder | prism | mesh
    params: dict[str, float] = field(default_factory=dict)
    position: tuple[float, float, float] = (0.3, 0.0, 0.0)
    quaternion: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    mesh_file: str | None = None
    colour: str = _METAL[0]

    def to_dict(self) -> dict:
        out = asdict(self)
        out["position"] = [float(v) for v in self.position]
        out["quaternion"] = [float(v) for v in self.quaternion]
        out["params"] = {k: float(v) for k, v in self.params.items()}
        return out

    @classmethod
    def from_dict(cls, data: dict) -> "ObjectSpec":
        return cls(
            cls=data["cls"],
            shape=data["shape"],
            params=dict(data.get("params", {})),
            position=tuple(data.get("position", (0.3, 0.0, 0.0))),
            quaternion=tuple(data.get("quaternion", (1.0, 0.0, 0.0, 0.0))),
            mesh_file=data.get("mesh_file"),
            colour=data.get("colour", _METAL[0]),
        )

    def grasp_point_local(self) -> np.ndarray:
        """Where a parallel gripper should squeeze: the handle's middle (local frame)."""
        p = self.params
        if self.shape in CUTLERY_KINDS:
            return np.array([-p["length"] / 2 + p["handle_length"] / 2, 0.0, 0.0])
        return np.zeros(3)

    def extent(self) -> tuple[float, float, float]:
        """Local bounding-box size (x, y, z); the body origin sits at the bottom centre."""
        p = self.params
        if self.shape in CUTLERY_KINDS:
            head = max(p["head_thickness"] * 3, 0.006) if self.shape == "spoon" else p["head_thickness"]  # bowl depth
            height = max(p["handle_thickness"], head)
            return (p["length"], max(p["handle_width"], p["head_width"]), height)
        s = p.get("size", p.get("scale", 0.05))
        return {"bar": (2 * s, s, s / 2)}.get(self.shape, (s, s, s))

    def grasp_width(self) -> float:
        """Width across the grasp point, for the oracle's clearance check."""
        p = self.params
        if self.shape in CUTLERY_KINDS:
            return p["handle_width"]
        return p.get("size", 0.03)


def _u(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    return float(rng.uniform(*bounds))


def sample_cutlery(kind: str, cfg: ObjectConfig, rng: np.random.Generator) -> ObjectSpec:
    length = _u(rng, getattr(cfg, f"{kind}_length"))
    params = {
        "length": length,
        "handle_length": length * float(rng.uniform(0.48, 0.56)),
        "handle_width": _u(rng, cfg.handle_width),
        "handle_thickness": _u(rng, cfg.handle_thickness),
        "head_thickness": _u(rng, cfg.head_thickness),
    }
    if kind == "fork":
        params["head_width"] = _u(rng, cfg.fork_head_width)
        params["tines"] = float(rng.integers(cfg.fork_tines[0], cfg.fork_tines[1] + 1))
        params["tine_fraction"] = float(rng.uniform(0.45, 0.6))  # of the head's length
    elif kind == "knife":
        params["head_width"] = _u(rng, cfg.knife_blade_width)
    else:
        params["head_width"] = _u(rng, cfg.spoon_bowl_width)
        params["bowl_length"] = _u(rng, cfg.spoon_bowl_length)
    return ObjectSpec(cls=kind, shape=kind, params=params, colour=_METAL[int(rng.integers(len(_METAL)))])


def sample_block(cfg: ObjectConfig, rng: np.random.Generator) -> ObjectSpec:
    shape = BLOCK_SHAPES[int(rng.integers(len(BLOCK_SHAPES)))]
    colour = _BLOCK_COLOURS[int(rng.integers(len(_BLOCK_COLOURS)))]
    return ObjectSpec(cls="block", shape=shape, params={"size": _u(rng, cfg.block_size)}, colour=colour)


def sample_mesh(cfg: ObjectConfig, rng: np.random.Generator) -> ObjectSpec:
    if not cfg.mesh_files:
        raise ValueError("object set 'mesh' needs ObjectConfig.mesh_files (OBJ/STL paths) and mesh_classes")
    i = int(rng.integers(len(cfg.mesh_files)))
    path = Path(cfg.mesh_files[i])
    if not path.is_file():
        raise FileNotFoundError(f"mesh file {path} does not exist: give an existing OBJ or STL path")
    return ObjectSpec(cls=cfg.mesh_classes[i], shape="mesh", params={"scale": cfg.mesh_scale}, mesh_file=str(path.resolve()))


# ---------------------------------------------------------------- MJCF

def _box(name: str, cls: str, centre: tuple[float, float, float], half: tuple[float, float, float], extra: str = "") -> str:
    c = " ".join(f"{v:.5f}" for v in centre)
    h = " ".join(f"{v:.5f}" for v in half)
    return f'<geom name="{name}" class="{cls}" type="box" pos="{c}" size="{h}" {extra}/>'


def _cutlery_geoms(spec: ObjectSpec, prefix: str) -> list[str]:
    p = spec.params
    length, hl, hw, ht, tt, head_w = (p["length"], p["handle_length"], p["handle_width"], p["handle_thickness"], p["head_thickness"], p["head_width"])
    x0 = -length / 2
    neck = 0.12 * (length - hl)
    head_len = length - hl - neck
    geoms = [
        _box(f"{prefix}_handle", "obj", (x0 + hl / 2, 0, ht / 2), (hl / 2, hw / 2, ht / 2)),
        _box(f"{prefix}_neck", "obj", (x0 + hl + neck / 2, 0, tt / 2), (neck / 2, min(hw, head_w) / 2.5, tt / 2)),
    ]
    head_x = x0 + hl + neck + head_len / 2
    if spec.shape == "knife":
        geoms.append(_box(f"{prefix}_blade", "obj", (head_x, 0, tt / 2), (head_len / 2, head_w / 2, tt / 2)))
    elif spec.shape == "spoon":
        depth = max(tt * 3, 0.006)
        bl = min(p["bowl_length"], head_len)
        geoms.append(
            f'<geom name="{prefix}_bowl" class="obj" type="ellipsoid" pos="{x0 + length - bl / 2:.5f} 0 {depth / 2:.5f}" '
            f'size="{bl / 2:.5f} {head_w / 2:.5f} {depth / 2:.5f}"/>'
        )
    else:  # fork: solid palm, then tines; a hidden plate under the tines carries their collision
        tines = int(p["tines"])
        tine_len = head_len * p["tine_fraction"]
        palm_len = head_len - tine_len
        geoms.append(_box(f"{prefix}_palm", "obj", (x0 + hl + neck + palm_len / 2, 0, tt / 2), (palm_len / 2, head_w / 2, tt / 2)))
        tine_x = x0 + length - tine_len / 2
        geoms.append(_box(f"{prefix}_tineplate", "obj_hidden", (tine_x, 0, tt / 2), (tine_len / 2, head_w / 2, tt / 2)))
        gap = head_w / (2 * tines - 1)
        for k in range(tines):
            y = -head_w / 2 + gap / 2 + 2 * gap * k
            geoms.append(_box(f"{prefix}_tine{k}", "obj_visual", (tine_x, y, tt / 2), (tine_len / 2, gap / 2, tt / 2)))
    return geoms


def _block_geoms(spec: ObjectSpec, prefix: str) -> list[str]:
    s = spec.params["size"]
    if spec.shape == "cube":
        return [_box(f"{prefix}_body", "block", (0, 0, s / 2), (s / 2, s / 2, s / 2))]
    if spec.shape == "bar":
        return [_box(f"{prefix}_body", "block", (0, 0, s / 4), (s, s / 2, s / 4))]
    if spec.shape == "cylinder":
        return [f'<geom name="{prefix}_body" class="block" type="cylinder" pos="0 0 {s / 2:.5f}" size="{s / 2:.5f} {s / 2:.5f}"/>']
    return [f'<geom name="{prefix}_body" class="block" type="mesh" mesh="{prefix}_prism"/>']


def asset_xml(spec: ObjectSpec, prefix: str) -> str:
    """Mesh assets this object needs (prisms, user meshes)."""
    if spec.shape == "prism":
        s = spec.params["size"]
        h = s / 2
        verts = [(-s / 2, -h, 0), (s / 2, -h, 0), (0, -h, s * 0.85), (-s / 2, h, 0), (s / 2, h, 0), (0, h, s * 0.85)]
        flat = " ".join(f"{v:.5f}" for vert in verts for v in vert)
        return f'<mesh name="{prefix}_prism" vertex="{flat}"/>'
    if spec.shape == "mesh":
        scale = spec.params.get("scale", 1.0)
        return f'<mesh name="{prefix}_mesh" file="{spec.mesh_file}" scale="{scale} {scale} {scale}"/>'
    return ""


def body_xml(spec: ObjectSpec, name: str) -> str:
    """A free body for the object, named `name`, at its pose."""
    if spec.shape in CUTLERY_KINDS:
        geoms = _cutlery_geoms(spec, name)
    elif spec.shape == "mesh":
        geoms = [f'<geom name="{name}_body" class="obj" type="mesh" mesh="{name}_mesh"/>']
    else:
        geoms = _block_geoms(spec, name)
    geoms = [g.replace("/>", f' rgba="{spec.colour}"/>', 1) if 'class="obj_hidden"' not in g else g for g in geoms]
    pos = " ".join(f"{v:.6f}" for v in spec.position)
    quat = " ".join(f"{v:.9f}" for v in spec.quaternion)
    return f'<body name="{name}" pos="{pos}" quat="{quat}"><freejoint name="{name}_free"/>{"".join(geoms)}</body>'


def defaults_xml(cfg: ObjectConfig, friction: float) -> str:
    """Object contacts use solref 0.01: the stiffer 0.004 that the pads need (they win by priority)
    left thin cutlery vibrating on the table and cost 3x the step time."""
    return f"""
    <default class="obj">
      <geom contype="1" conaffinity="1" group="2" density="{cfg.density}" material="metal" condim="4"
            friction="{friction} 0.01 0.001" solref="0.01 1"/>
    </default>
    <default class="obj_hidden">
      <geom contype="1" conaffinity="1" group="3" density="{cfg.density}" condim="4" rgba="0 0 0 0"
            friction="{friction} 0.01 0.001" solref="0.01 1"/>
    </default>
    <default class="obj_visual">
      <geom contype="0" conaffinity="0" group="2" density="0" material="metal"/>
    </default>
    <default class="block">
      <geom contype="1" conaffinity="1" group="2" density="{cfg.block_density}" condim="4"
            friction="{friction} 0.01 0.001" solref="0.01 1"/>
    </default>"""
