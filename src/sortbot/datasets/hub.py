"""`sortbot datasets push`: lerobot's `push_to_hub`, with a dry run and a fast, clear failure offline
(instead of a long hang in the HTTP client)."""

from __future__ import annotations

import os
import socket
from pathlib import Path
from urllib.parse import urlparse

from sortbot.datasets.lerobot_store import read_collection
from sortbot.datasets.summary import resolve_root

HUB_ENDPOINT = "https://huggingface.co"
REACH_TIMEOUT_S = 5.0


def files_to_upload(root: Path) -> list[tuple[str, int]]:
    """(relative path, bytes) of what push_to_hub uploads: the whole dataset folder."""
    root = resolve_root(root)
    read_collection(root)
    return sorted((str(p.relative_to(root)), p.stat().st_size) for p in root.rglob("*")
                  if p.is_file() and not p.name.endswith(".tmp"))


def _check_hub_reachable(endpoint: str) -> None:
    if os.environ.get("HF_HUB_OFFLINE", "0") not in ("0", "", "false", "False"):
        raise ConnectionError("HF_HUB_OFFLINE is set: unset it to push, or use --dry-run to list what would be uploaded")
    url = urlparse(endpoint)
    try:
        socket.create_connection((url.hostname, url.port or 443), timeout=REACH_TIMEOUT_S).close()
    except OSError as err:
        raise ConnectionError(f"cannot reach {endpoint} ({err.__class__.__name__}): check the network, "
                              "or use --dry-run to list what would be uploaded") from None


def push_dataset(path: Path, repo_id: str, private: bool = False, dry_run: bool = False) -> list[tuple[str, int]]:
    """Upload with lerobot's push_to_hub under `repo_id` (ORG/NAME). Returns the file list."""
    if repo_id.count("/") != 1 or not all(repo_id.split("/")):
        raise ValueError(f"--repo-id must look like ORG/NAME, not {repo_id!r}")
    root = resolve_root(path)
    files = files_to_upload(root)
    if dry_run:
        return files
    _check_hub_reachable(os.environ.get("HF_ENDPOINT", HUB_ENDPOINT))
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    ds = LeRobotDataset(repo_id, root=root)
    ds.push_to_hub(private=private, tags=["sortbot", "ur3", "mujoco", "cutlery"])
    return files
