"""Read a sortbot episode MCAP back with the `mcap` reader (protobuf for Foxglove schemas, JSON
for sortbot's own), tolerating a file cut short by a crash: everything before the damage is
returned and the damage is reported, so `replay` can say what it could still read.
"""

from __future__ import annotations

import io
import json
import struct
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sortbot.datasets.mcap_writer import (
    EPISODE_METADATA, TOPIC_ACTION, TOPIC_DEPTH, TOPIC_LABELS, TOPIC_OUTCOME, TOPIC_RGB, TOPIC_SCENE,
)


class McapReadError(ValueError):
    """The file is not a readable MCAP log (wrong format, or damaged before its first message)."""


@dataclass
class Observation:
    """One logged observation: images, labels and scene, decoded lazily from the raw messages."""

    step: int
    log_time_ns: int
    rgb_bytes: bytes | None = None
    depth_msg: object | None = None
    labels: dict | None = None
    scene: object | None = None

    def rgb(self) -> np.ndarray:
        from PIL import Image

        if self.rgb_bytes is None:
            raise McapReadError(f"observation {self.step} has no {TOPIC_RGB} image")
        return np.asarray(Image.open(io.BytesIO(self.rgb_bytes)).convert("RGB"))

    def depth(self) -> np.ndarray:
        m = self.depth_msg
        if m is None:
            raise McapReadError(f"observation {self.step} has no {TOPIC_DEPTH} image")
        if m.encoding != "32FC1":
            raise McapReadError(f"{TOPIC_DEPTH} has encoding {m.encoding!r}, expected 32FC1")
        return np.frombuffer(m.data, dtype="<f4").reshape(m.height, m.width)


@dataclass
class EpisodeLog:
    path: Path
    metadata: dict = field(default_factory=dict)
    schemas: dict[str, str] = field(default_factory=dict)  # topic -> schema name
    counts: dict[str, int] = field(default_factory=dict)  # topic -> messages read
    observations: list[Observation] = field(default_factory=list)
    actions: list[dict] = field(default_factory=list)
    outcomes: list[dict] = field(default_factory=list)
    calibration: object | None = None
    error: str | None = None  # set when the file is damaged; the lists hold what came before it

    @property
    def complete(self) -> bool:
        return self.error is None and bool(self.outcomes) and bool(self.outcomes[-1].get("done"))


def read_episode(path: Path, images: bool = True) -> EpisodeLog:
    """Every message of one episode file. Raises McapReadError when nothing at all is readable;
    a damaged tail is reported in `EpisodeLog.error` instead."""
    from mcap.exceptions import McapError
    from mcap.records import Channel, Message, Metadata, Schema
    from mcap.stream_reader import StreamReader
    from mcap_protobuf.decoder import DecoderFactory

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path} does not exist: give an episode_NNNNNN.mcap written by `sortbot collect`")
    log = EpisodeLog(path=path)
    decoders = DecoderFactory()
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    decode_fns: dict[int, object] = {}
    counts: dict[str, int] = defaultdict(int)
    current: dict[int, Observation] = {}
    records = 0
    with open(path, "rb") as f:
        try:
            for record in StreamReader(f, validate_crcs=True).records:
                records += 1
                if isinstance(record, Schema):
                    schemas[record.id] = record
                elif isinstance(record, Channel):
                    channels[record.id] = record
                    schema = schemas.get(record.schema_id)
                    log.schemas[record.topic] = schema.name if schema else ""
                    if record.message_encoding == "protobuf" and schema is not None:
                        decode_fns[record.id] = decoders.decoder_for(record.message_encoding, schema)
                elif isinstance(record, Metadata) and record.name == EPISODE_METADATA:
                    log.metadata = {k: _maybe_json(v) for k, v in record.metadata.items()}
                elif isinstance(record, Message):
                    channel = channels[record.channel_id]
                    counts[channel.topic] += 1
                    _route(log, current, channel, record, decode_fns.get(record.channel_id), images)
        except (McapError, EOFError, ValueError, KeyError, OSError, struct.error) as err:
            if records == 0 or not channels:
                raise McapReadError(f"{path} is not a readable MCAP log ({type(err).__name__}{': ' + str(err) if str(err) else ''}): "
                                    "give an episode_NNNNNN.mcap written by `sortbot collect`") from None
            log.error = (f"damaged after {sum(counts.values())} messages ({type(err).__name__}{': ' + str(err) if str(err) else ''}); "
                         "the file was probably cut short by a killed collector")
    log.counts = dict(counts)
    log.observations = [current[t] for t in sorted(current)]
    return log


def _route(log: EpisodeLog, current: dict[int, Observation], channel, message, decode, images: bool) -> None:
    topic, t = channel.topic, message.log_time
    if topic == TOPIC_ACTION:
        log.actions.append(json.loads(message.data))
    elif topic == TOPIC_OUTCOME:
        log.outcomes.append(json.loads(message.data))
    elif topic in (TOPIC_RGB, TOPIC_DEPTH, TOPIC_LABELS, TOPIC_SCENE):
        obs = current.setdefault(t, Observation(step=len(current), log_time_ns=t))
        if topic == TOPIC_LABELS:
            obs.labels = json.loads(message.data)
            obs.step = int(obs.labels.get("step", obs.step))
        elif not images:
            return
        elif topic == TOPIC_RGB:
            obs.rgb_bytes = decode(message.data).data
        elif topic == TOPIC_DEPTH:
            obs.depth_msg = decode(message.data)
        else:
            obs.scene = decode(message.data)
    elif decode is not None and log.calibration is None and channel.topic.endswith("calibration"):
        log.calibration = decode(message.data)


def _maybe_json(value: str):
    try:
        return json.loads(value)
    except (json.JSONDecodeError, TypeError):
        return value
