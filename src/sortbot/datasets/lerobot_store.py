"""A LeRobot v3 dataset that survives `kill -9` and stays cheap to append to for hours.

lerobot keeps parquet writers open and buffers episode metadata until `finalize()`, so a killed
recorder leaves an unreadable dataset; and reopening a finalized dataset (`resume()`) reloads all
episode metadata, so committing episode by episode that way costs time and memory that grow
with the dataset. Instead every episode is written by lerobot (`create`, `add_frame`,
`save_episode`, `finalize`) as its own small dataset in a staging folder next to the dataset and
committed there by one atomic file; every `fold_every` episodes, and on close, the staged
episodes are folded into the dataset with lerobot's `aggregate_datasets` into a fresh folder that
then replaces the old one by rename. A run killed at any point keeps every committed episode:
opening the store again finishes or undoes a half-done fold and drops a half-written episode.

    DIR/lerobot/                    the dataset (stock LeRobotDataset)
    DIR/lerobot.staging/episode_N/  committed episodes not folded yet (each a stock dataset)

sortbot's own metadata sits next to lerobot's in `meta/`: `sortbot.json` (how the data was
collected: policy, scene and env config, versions) and `sortbot_episodes.jsonl` (seed,
scene and end of every episode).
"""

from __future__ import annotations

import contextlib
import ctypes
import gc
import json
import shutil
import tempfile
from dataclasses import asdict
from pathlib import Path

import av

from sortbot.config import DatasetConfig
from sortbot.datasets.features import DEPTH_KEY, RGB_KEY, dataset_features
from sortbot.datasets.thread_scheduling import scheduling_kept

COLLECTION_FILE = "meta/sortbot.json"
EPISODES_FILE = "meta/sortbot_episodes.jsonl"
STAGED_RECORD = "meta/sortbot_staged.json"  # its presence commits a staged episode
DEFAULT_REPO_ID = "local/sortbot"


class NotADatasetError(ValueError):
    """The folder holds no sortbot LeRobot dataset."""


def _quiet() -> None:
    """Our own progress bar is enough: silence SVT-AV1's banner and HF datasets' per-episode bars."""
    import os

    import datasets

    os.environ.setdefault("SVT_LOG", "1")  # errors only
    datasets.disable_progress_bars()
    av.logging.set_level(av.logging.ERROR)  # FFmpeg's muxer warnings about made-up timestamps


def _encoders(config: DatasetConfig):
    from lerobot.configs.video import DepthEncoderConfig, RGBEncoderConfig

    rgb = RGBEncoderConfig(crf=config.rgb_crf)
    depth = DepthEncoderConfig(depth_min=config.depth_min, depth_max=config.depth_max, use_log=config.depth_use_log,
                               extra_options={"x265-params": "lossless=1:log-level=error"})  # x265 chats on stderr
    return rgb, depth


def staging_dir(root: Path) -> Path:
    return Path(root).with_name(Path(root).name + ".staging")


def _folding_dir(root: Path) -> Path:
    return Path(root).with_name(Path(root).name + ".folding")


def _old_dir(root: Path) -> Path:
    return Path(root).with_name(Path(root).name + ".old")


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


def staged_episodes(root: Path) -> list[Path]:
    """Committed episodes waiting in the staging folder, in index order."""
    folder = staging_dir(root)
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.glob("episode_*") if (p / STAGED_RECORD).is_file())


def total_episodes(root: Path) -> int:
    return int(json.loads((Path(root) / "meta" / "info.json").read_text())["total_episodes"])


def release_memory() -> None:
    """Give freed arrow/video buffers back to the OS: without this, glibc and arrow's pool keep
    every episode's peak allocations and a long collection's RSS creeps up (~0.7 MB/episode)."""
    import pyarrow

    gc.collect()
    pyarrow.default_memory_pool().release_unused()
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL("libc.so.6").malloc_trim(0)


@contextlib.contextmanager
def _lerobot_chatter_held():
    """lerobot's aggregation and HF datasets print progress bars of their own for every episode;
    they are held back (our caller shows one bar) and shown only if the work fails."""
    import io
    import sys

    held = io.StringIO()
    try:
        with contextlib.redirect_stderr(held):
            yield
    except BaseException:
        sys.stderr.write(held.getvalue())
        raise


@contextlib.contextmanager
def _private_hf_cache():
    """lerobot loads episode metadata through HF datasets, which writes an arrow cache per load
    into ~/.cache/huggingface; ours go to a temporary folder removed afterwards."""
    import datasets

    default = datasets.config.HF_DATASETS_CACHE
    folder = Path(tempfile.mkdtemp(prefix="sortbot-hf-cache-"))
    datasets.config.HF_DATASETS_CACHE = folder
    try:
        yield folder
    finally:
        datasets.config.HF_DATASETS_CACHE = default
        shutil.rmtree(folder, ignore_errors=True)


class EpisodeStore:
    """Append-only, episode-committed writer of one sortbot LeRobot dataset."""

    def __init__(self, root: Path, config: DatasetConfig, camera: dict, repo_id: str = DEFAULT_REPO_ID):
        self.root = Path(root)
        self.config = config
        self.camera = camera
        self.repo_id = repo_id
        _quiet()

    # -- opening -----------------------------------------------------------------------------
    @classmethod
    def create(cls, root: Path, config: DatasetConfig, collection: dict, camera: dict,
               repo_id: str = DEFAULT_REPO_ID) -> "EpisodeStore":
        """A new, empty dataset at `root` (which must not exist). `camera` goes into the
        camera features' info (intrinsics, pose); `collection` into meta/sortbot.json."""
        store = cls(root, config, camera, repo_id)
        shutil.rmtree(staging_dir(root), ignore_errors=True)
        store._new_dataset(store.root).finalize()  # an empty dataset: valid, and holds sortbot.json
        record = {**collection, "repo_id": repo_id, "dataset_config": asdict(config)}
        _atomic_write(store.root / COLLECTION_FILE, json.dumps(record, indent=1, default=str))
        (store.root / EPISODES_FILE).touch()
        return store

    @classmethod
    def open(cls, root: Path) -> "EpisodeStore":
        """Reopen for appending, after finishing or undoing whatever a killed run left half done."""
        recover(root)
        collection = read_collection(root)
        return cls(root, DatasetConfig(**collection["dataset_config"]), recorded_camera(root), collection["repo_id"])

    @property
    def committed_episodes(self) -> int:
        return total_episodes(self.root) + len(staged_episodes(self.root))

    # -- writing -----------------------------------------------------------------------------
    def append(self, frames: list[dict], task: str, episode: dict) -> int:
        """Write and commit one episode; returns its index. `episode` goes to sortbot_episodes.jsonl."""
        if not frames:
            raise ValueError("an episode needs at least one frame (the scene was already done at reset)")
        index = self.committed_episodes
        folder = staging_dir(self.root) / f"episode_{index:06d}"
        for attempt in range(self.config.encode_attempts):
            try:
                self._write_staged(folder, frames, task)
                break
            except av.error.FFmpegError:  # x265 fails now and then on a clip it encodes fine the next time
                if attempt + 1 == self.config.encode_attempts:
                    raise
        _atomic_write(folder / STAGED_RECORD, json.dumps({"episode_index": index, **episode}, default=str))  # commit
        if len(staged_episodes(self.root)) >= self.config.fold_every:
            self.fold()
        release_memory()
        return index

    def _write_staged(self, folder: Path, frames: list[dict], task: str) -> None:
        shutil.rmtree(folder, ignore_errors=True)  # a half-written try at this episode
        folder.parent.mkdir(parents=True, exist_ok=True)
        with _lerobot_chatter_held(), _private_hf_cache(), scheduling_kept():  # SVT-AV1 goes real-time as root
            dataset = self._new_dataset(folder)
            for frame in frames:
                dataset.add_frame({**frame, "task": task})
            dataset.save_episode(parallel_encoding=False)  # lerobot would fork this (big, threaded) process per episode
            dataset.finalize()
        if len(frames) == 1:
            _float_stats_of_single_frame(folder)

    def fold(self) -> int:
        """Move the staged episodes into the dataset (lerobot's aggregation into a fresh folder,
        swapped in by rename). Returns how many were folded."""
        staged = staged_episodes(self.root)
        if not staged:
            return 0
        from lerobot.datasets.aggregate import aggregate_datasets

        folding = _folding_dir(self.root)
        shutil.rmtree(folding, ignore_errors=True)
        sources = ([self.root] if total_episodes(self.root) > 0 else []) + staged
        with _lerobot_chatter_held(), _private_hf_cache():
            aggregate_datasets(repo_ids=[f"local/sortbot_part_{k}" for k in range(len(sources))],
                               aggr_repo_id=self.repo_id, roots=sources, aggr_root=folding,
                               concatenate_videos=False)  # remuxing short AV1/HEVC clips fails on some streams
        shutil.copy2(self.root / COLLECTION_FILE, folding / COLLECTION_FILE)
        records = read_episode_records(self.root) + [json.loads((p / STAGED_RECORD).read_text()) for p in staged]
        _write_episode_records(folding, records)
        old = _old_dir(self.root)
        shutil.rmtree(old, ignore_errors=True)
        self.root.rename(old)
        folding.rename(self.root)  # the commit point of the fold
        shutil.rmtree(old)
        for folder in staged:
            shutil.rmtree(folder)
        release_memory()
        return len(staged)

    def close(self) -> None:
        """Fold what is staged: the dataset then holds every committed episode."""
        self.fold()
        with contextlib.suppress(OSError):
            staging_dir(self.root).rmdir()  # only when empty

    def _new_dataset(self, root: Path):
        from lerobot.datasets.lerobot_dataset import LeRobotDataset

        feats = dataset_features(self.camera["camera.height"], self.camera["camera.width"], self.config)
        for key in (RGB_KEY, DEPTH_KEY):
            feats[key].setdefault("info", {}).update(self.camera)
        rgb, depth = _encoders(self.config)
        return LeRobotDataset.create(self.repo_id, fps=self.config.fps, features=feats, root=root,
                                     robot_type="ur3", rgb_encoder=rgb, depth_encoder=depth)


def _float_stats_of_single_frame(root: Path) -> None:
    """lerobot computes a 1-frame episode's min/max/quantiles in the feature's own dtype (bool for
    `next.done`) but a longer one's as float64; its aggregation then cannot put both in one parquet
    column ("Cannot mix NumPy dtypes float64 and bool"). Store them as float64 like the others."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    for path in sorted((Path(root) / "meta" / "episodes").rglob("*.parquet")):
        table = pq.read_table(path)
        fields = [pa.field(f.name, pa.list_(pa.float64())) if f.name.startswith("stats/") and f.type == pa.list_(pa.bool_())
                  else f for f in table.schema]
        fixed = pa.schema(fields, metadata=table.schema.metadata)
        if fixed != table.schema:
            tmp = path.with_name(path.name + ".tmp")
            pq.write_table(table.cast(fixed), tmp)
            tmp.replace(path)


def recover(root: Path) -> None:
    """Finish or undo what a killed run left half done.

    A fold killed before its swap leaves `.folding` (dropped: the staged episodes are still
    there); one killed between the two renames leaves `.old` + a complete `.folding`. Staged
    folders without their commit record, or already folded, are dropped."""
    root = Path(root)
    folding, old = _folding_dir(root), _old_dir(root)
    if not root.exists() and old.exists():
        (folding if folding.exists() else old).rename(root)
    for leftover in (folding, old):
        shutil.rmtree(leftover, ignore_errors=True)
    folder = staging_dir(root)
    if folder.is_dir():
        expected = total_episodes(root)
        for path in sorted(folder.glob("episode_*")):
            if (path / STAGED_RECORD).is_file() and path.name == f"episode_{expected:06d}":
                expected += 1
                continue
            shutil.rmtree(path)  # half written, already folded, or after a gap


def recorded_camera(root: Path) -> dict:
    """The camera entries (`features.camera_info`) lerobot keeps in the RGB feature's info."""
    info = json.loads((Path(root) / "meta" / "info.json").read_text())
    video_info = info["features"][RGB_KEY].get("info", {})
    return {k: v for k, v in video_info.items() if k.startswith("camera.")}


def _write_episode_records(root: Path, records: list[dict]) -> None:
    _atomic_write(Path(root) / EPISODES_FILE, "".join(json.dumps(r, default=str) + "\n" for r in records))


def _atomic_write(path: Path, text: str) -> None:
    """Write via a temporary file and rename, so readers see the old or the new file, never half."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    tmp.replace(path)
