"""A LeRobot v3 dataset that survives `kill -9`: every episode is written by lerobot itself
(`create`/`resume`, `add_frame`, `save_episode`, `finalize`) and committed before the next starts.

lerobot keeps parquet writers open across episodes and buffers episode metadata until
`finalize()`, so a killed recorder leaves an unreadable dataset. Here each episode is finalized
(its own data/video files), and `meta/` is copied aside while an episode is being committed; a
run that dies in that window is rolled back to the last committed episode on the next open.

sortbot's own metadata sits next to lerobot's in `meta/`: `sortbot.json` (how the data was
collected: policy, scene and env config, versions) and `sortbot_episodes.jsonl` (seed, scene and
end of every episode).
"""

from __future__ import annotations

import json
import shutil
import tempfile
from dataclasses import asdict
from pathlib import Path

from sortbot.config import DatasetConfig
from sortbot.datasets.features import DEPTH_KEY, RGB_KEY, dataset_features

COLLECTION_FILE = "meta/sortbot.json"
EPISODES_FILE = "meta/sortbot_episodes.jsonl"
BACKUP_DIR = ".meta_being_committed"
DEFAULT_REPO_ID = "local/sortbot"


class NotADatasetError(ValueError):
    """The folder holds no sortbot LeRobot dataset."""


def _quiet() -> None:
    """Our own progress bar is enough: silence SVT-AV1's banner and HF datasets' per-episode bars."""
    import os

    import datasets

    os.environ.setdefault("SVT_LOG", "1")  # errors only
    datasets.disable_progress_bars()


def _encoders(config: DatasetConfig):
    from lerobot.configs.video import DepthEncoderConfig, RGBEncoderConfig

    rgb = RGBEncoderConfig(crf=config.rgb_crf)
    depth = DepthEncoderConfig(depth_min=config.depth_min, depth_max=config.depth_max, use_log=config.depth_use_log,
                               extra_options={"x265-params": "lossless=1:log-level=error"})  # x265 chats on stderr
    return rgb, depth


def is_dataset(root: Path) -> bool:
    return (Path(root) / "meta" / "info.json").is_file()


def read_collection(root: Path) -> dict:
    """`meta/sortbot.json`, or a clear error when `root` is not a sortbot dataset."""
    root = Path(root)
    path = root / COLLECTION_FILE
    if not is_dataset(root):
        raise NotADatasetError(f"{root} is not a LeRobot dataset (no meta/info.json): point at the folder `sortbot collect` wrote (DIR/lerobot)")
    if not path.is_file():
        raise NotADatasetError(f"{root} is a LeRobot dataset but not one sortbot collected (no {COLLECTION_FILE})")
    return json.loads(path.read_text())


def read_episode_records(root: Path) -> list[dict]:
    path = Path(root) / EPISODES_FILE
    if not path.is_file():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


class EpisodeStore:
    """Append-only, episode-committed writer of one sortbot LeRobot dataset."""

    def __init__(self, root: Path, config: DatasetConfig, repo_id: str = DEFAULT_REPO_ID):
        self.root = Path(root)
        self.config = config
        self.repo_id = repo_id
        self._dataset = None  # the lerobot writer of the episode being committed
        # lerobot's resume() converts all episode metadata to a new HF arrow cache every time:
        # per-episode commits would grow ~/.cache/huggingface quadratically, so ours go here
        self._hf_cache = Path(tempfile.mkdtemp(prefix="sortbot-hf-cache-"))
        _quiet()

    # -- opening -----------------------------------------------------------------------------
    @classmethod
    def create(cls, root: Path, config: DatasetConfig, collection: dict, camera: dict,
               repo_id: str = DEFAULT_REPO_ID) -> "EpisodeStore":
        """A new, empty dataset at `root` (which must not exist). `camera` goes into the
        camera features' info (intrinsics, pose); `collection` into meta/sortbot.json."""
        from lerobot.datasets.lerobot_dataset import LeRobotDataset

        store = cls(root, config, repo_id)
        feats = dataset_features(camera["camera.height"], camera["camera.width"], config)
        for key in (RGB_KEY, DEPTH_KEY):
            feats[key].setdefault("info", {}).update(camera)
        rgb, depth = _encoders(config)
        store._dataset = LeRobotDataset.create(repo_id, fps=config.fps, features=feats, root=store.root,
                                               robot_type="ur3", rgb_encoder=rgb, depth_encoder=depth)
        record = {**collection, "repo_id": repo_id, "dataset_config": asdict(config)}
        _atomic_write(store.root / COLLECTION_FILE, json.dumps(record, indent=1, default=str))
        (store.root / EPISODES_FILE).touch()
        return store

    @classmethod
    def open(cls, root: Path) -> "EpisodeStore":
        """Reopen for appending; an episode whose commit was cut short is rolled back first."""
        collection = read_collection(root)
        store = cls(root, DatasetConfig(**collection["dataset_config"]), collection["repo_id"])
        store.recover()
        return store

    @property
    def committed_episodes(self) -> int:
        info = json.loads((self.root / "meta" / "info.json").read_text())
        return int(info["total_episodes"])

    # -- writing -----------------------------------------------------------------------------
    def append(self, frames: list[dict], task: str, episode: dict) -> int:
        """Write and commit one episode; returns its index. `episode` goes to sortbot_episodes.jsonl."""
        if not frames:
            raise ValueError("an episode needs at least one frame (the scene was already done at reset)")
        index = self.committed_episodes
        backup = self.root / BACKUP_DIR
        shutil.rmtree(backup, ignore_errors=True)
        shutil.copytree(self.root / "meta", backup)  # the committed state, restored if we die below
        dataset = self._dataset or self._resume()
        self._dataset = None
        for frame in frames:
            dataset.add_frame({**frame, "task": task})
        dataset.save_episode()
        dataset.finalize()
        records = read_episode_records(self.root)[:index]
        _write_episode_records(self.root, [*records, {"episode_index": index, **episode}])
        shutil.rmtree(backup)  # the commit point
        shutil.rmtree(self._hf_cache, ignore_errors=True)
        return index

    def close(self) -> None:
        """Release an opened-but-unused lerobot writer (an empty dataset stays valid)."""
        if self._dataset is not None:
            self._dataset.finalize()
            self._dataset = None
        shutil.rmtree(self._hf_cache, ignore_errors=True)

    def _resume(self):
        from lerobot.datasets.lerobot_dataset import LeRobotDataset

        import datasets

        rgb, depth = _encoders(self.config)
        default_cache = datasets.config.HF_DATASETS_CACHE
        datasets.config.HF_DATASETS_CACHE = self._hf_cache
        try:
            return LeRobotDataset.resume(self.repo_id, root=self.root, rgb_encoder=rgb, depth_encoder=depth)
        finally:
            datasets.config.HF_DATASETS_CACHE = default_cache

    # -- recovery ----------------------------------------------------------------------------
    def recover(self) -> bool:
        """Roll back an interrupted commit: restore meta/, drop files no episode refers to.
        Returns True when something was rolled back."""
        backup = self.root / BACKUP_DIR
        rolled_back = backup.is_dir()
        if rolled_back:
            shutil.rmtree(self.root / "meta")
            backup.rename(self.root / "meta")
        shutil.rmtree(self.root / "images", ignore_errors=True)  # lerobot's frame staging area
        self._drop_unreferenced_files()
        records = read_episode_records(self.root)
        if len(records) > self.committed_episodes:
            _write_episode_records(self.root, records[: self.committed_episodes])
        return rolled_back

    def _drop_unreferenced_files(self) -> None:
        from lerobot.datasets.io_utils import load_episodes, load_info

        info = load_info(self.root)
        referenced: set[Path] = set()
        if info.total_episodes > 0:
            episodes = load_episodes(self.root)
            for ep in episodes:
                referenced.add(self.root / info.data_path.format(chunk_index=ep["data/chunk_index"], file_index=ep["data/file_index"]))
                for key in _video_keys(info):
                    referenced.add(self.root / info.video_path.format(
                        video_key=key, chunk_index=ep[f"videos/{key}/chunk_index"], file_index=ep[f"videos/{key}/file_index"]))
        for folder, pattern in (("data", "*.parquet"), ("videos", "*.mp4")):
            for path in (self.root / folder).rglob(pattern) if (self.root / folder).is_dir() else []:
                if path not in referenced:
                    path.unlink()


def _video_keys(info) -> list[str]:
    return [k for k, ft in info.features.items() if ft.get("dtype") == "video"]


def _write_episode_records(root: Path, records: list[dict]) -> None:
    _atomic_write(Path(root) / EPISODES_FILE, "".join(json.dumps(r, default=str) + "\n" for r in records))


def _atomic_write(path: Path, text: str) -> None:
    """Write via a temporary file and rename, so readers see the old or the new file, never half."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    tmp.replace(path)
