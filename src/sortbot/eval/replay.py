"""`sortbot replay FILE.mcap`: understand an episode after the fact: a table of what was tried and
what came of it, PNG frames with the labels and the action drawn, a contact sheet, an MP4."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sortbot.datasets.mcap_reader import EpisodeLog, McapReadError, read_episode

ACTION_ARROW_M = 0.05  # length of the drawn push direction / gripper closing axis
SHEET_COLUMNS = 6
SHEET_THUMB_WIDTH = 320
_CLASS_RGB = {"fork": (230, 80, 50), "knife": (50, 150, 230), "spoon": (70, 200, 70), "block": (220, 180, 40)}


def result_text(action: dict, outcome: dict | None) -> str:
    """What came of one action, in words (an outcome may be missing in a cut file)."""
    if not outcome:
        return "(no outcome: file cut here)"
    if not outcome.get("executed", True):
        return f"not executed ({outcome.get('failure_reason')})"
    if action["primitive"] == "grasp":
        if not outcome.get("grasp_success"):
            return "missed"
        return (f"held {outcome.get('held_object_class')} -> {outcome.get('placed_bin')} bin"
                + (" (right)" if outcome.get("well_placed") else " (WRONG)"))
    return "moved" if outcome.get("push_moved") else "nothing moved"


def step_rows(log: EpisodeLog) -> list[dict]:
    """One row per decision: the action and its outcome."""
    outcomes = {o["step"]: o for o in log.outcomes}
    rows = []
    for a in log.actions:
        o = outcomes.get(a["step"], {})
        rows.append({"step": a["step"], "primitive": a["primitive"], "position": a["position"], "angle": a["angle"],
                     "place_bin": a.get("place_bin"), "result": result_text(a, o), "reward": o.get("reward"),
                     "sim_s": o.get("sim_time_s"), "wall_s": o.get("wall_time_s"), "done": o.get("done"),
                     "end_reason": o.get("end_reason")})
    return rows


def summary(log: EpisodeLog) -> dict:
    grasps = [o for o in log.outcomes if o["primitive"] == "grasp"]
    pushes = [o for o in log.outcomes if o["primitive"] == "push"]
    return {
        "file": str(log.path), "complete": log.complete, "error": log.error, "seed": log.metadata.get("seed"),
        "policy": log.metadata.get("policy"), "actions": len(log.actions), "observations": len(log.observations),
        "grasps": len(grasps), "grasp_success": sum(o["grasp_success"] for o in grasps),
        "well_placed": sum(o["well_placed"] for o in grasps), "pushes": len(pushes),
        "push_moved": sum(o["push_moved"] for o in pushes),
        "sim_time_s": sum(o["sim_time_s"] for o in log.outcomes), "wall_time_s": sum(o.get("wall_time_s", 0.0) for o in log.outcomes),
        "end_reason": log.outcomes[-1].get("end_reason") if log.outcomes else None,
        "topics": log.counts, "schemas": log.schemas,
    }


def _project(point, calibration, camera_pose: np.ndarray) -> tuple[float, float] | None:
    """Base-frame point -> pixel, with the logged calibration and camera pose (camera -> base)."""
    k = np.array(calibration.K, dtype=float).reshape(3, 3)
    p = camera_pose[:3, :3].T @ (np.asarray(point, dtype=float) - camera_pose[:3, 3])
    if p[2] <= 0:
        return None
    uv = k @ (p / p[2])
    return float(uv[0]), float(uv[1])


def draw_frame(log: EpisodeLog, obs, action: dict | None, outcome: dict | None, camera_pose: np.ndarray):
    """One observation with its label boxes and the action taken from it drawn on."""
    from PIL import Image, ImageDraw

    image = Image.fromarray(obs.rgb())
    draw = ImageDraw.Draw(image)
    for lab in (obs.labels or {}).get("objects", []):
        colour = _CLASS_RGB.get(lab["cls"], (200, 200, 200))
        draw.rectangle(lab["box"], outline=colour, width=2)
        draw.text((lab["box"][0] + 2, lab["box"][1] + 1), lab["cls"], fill=colour)
    caption = f"step {obs.step}"
    if action is not None and log.calibration is not None:
        x, y, z = action["position"]
        centre = _project((x, y, z), log.calibration, camera_pose)
        c, s = np.cos(action["angle"]), np.sin(action["angle"])
        ends = [_project((x + sign * ACTION_ARROW_M * c, y + sign * ACTION_ARROW_M * s, z), log.calibration, camera_pose)
                for sign in (-1, 1)] if action["primitive"] == "grasp" else \
               [centre, _project((x + ACTION_ARROW_M * c, y + ACTION_ARROW_M * s, z), log.calibration, camera_pose)]
        colour = (255, 0, 255) if action["primitive"] == "grasp" else (255, 255, 0)
        if centre and all(ends):
            draw.line([*ends[0], *ends[1]], fill=colour, width=3)
            draw.ellipse([centre[0] - 5, centre[1] - 5, centre[0] + 5, centre[1] + 5], outline=colour, width=2)
        caption += f": {action['primitive']}" + (f" -> {action['place_bin']} bin" if action.get("place_bin") else "")
        if outcome is not None:
            caption += f" | {result_text(action, outcome)}"
    draw.rectangle([0, 0, image.width, 14], fill=(0, 0, 0))
    draw.text((3, 1), caption, fill=(255, 255, 255))
    return image


def camera_pose_of(log: EpisodeLog) -> np.ndarray:
    """Camera -> base transform, as the collector wrote it into the episode metadata."""
    pose = log.metadata.get("camera_pose")
    if pose is None:
        raise McapReadError(f"{log.path} has no camera pose in its metadata")
    return np.asarray(pose, dtype=float)


def draw_frames(log: EpisodeLog) -> list:
    """Every observation drawn (PIL images), once, for PNGs, the contact sheet and the video."""
    pose = camera_pose_of(log)
    actions = {a["step"]: a for a in log.actions}
    outcomes = {o["step"]: o for o in log.outcomes}
    return [draw_frame(log, obs, actions.get(obs.step), outcomes.get(obs.step), pose) for obs in log.observations]


def write_frames(images: list, out: Path) -> list[Path]:
    """frame_NNNN.png per drawn observation and contact_sheet.png (all frames, thumbnails)."""
    from PIL import Image

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths, thumbs = [], []
    for k, image in enumerate(images):
        path = out / f"frame_{k:04d}.png"
        image.save(path)
        paths.append(path)
        scale = SHEET_THUMB_WIDTH / image.width
        thumbs.append(image.resize((SHEET_THUMB_WIDTH, int(image.height * scale))))
    if thumbs:
        cols = min(SHEET_COLUMNS, len(thumbs))
        rows = (len(thumbs) + cols - 1) // cols
        tw, th = thumbs[0].size
        sheet = Image.new("RGB", (cols * tw, rows * th), (20, 20, 20))
        for k, thumb in enumerate(thumbs):
            sheet.paste(thumb, ((k % cols) * tw, (k // cols) * th))
        sheet.save(out / "contact_sheet.png")
        paths.append(out / "contact_sheet.png")
    return paths


def write_video(images: list, path: Path, fps: float = 2.0) -> Path:
    """An MP4 of the drawn frames (PyAV, H.264 when the build has it, else MPEG-4 part 2)."""
    import av

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    codec = "libx264" if "libx264" in av.codecs_available else "mpeg4"
    with av.open(str(path), mode="w") as container:
        stream = container.add_stream(codec, rate=int(round(fps)))
        stream.pix_fmt = "yuv420p"
        if images:
            stream.width, stream.height = images[0].width, images[0].height
        for image in images:
            for packet in stream.encode(av.VideoFrame.from_image(image)):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    return path


def load(path: Path, images: bool) -> EpisodeLog:
    log = read_episode(path, images=images)
    if not log.observations and not log.actions:
        raise McapReadError(f"{path} holds no sortbot messages")
    return log
