"""Read a Rerun ``.rrd`` recording back: which entities it holds, over which times.

Used by ``hsqbench view`` (to refuse a file Rerun cannot read before starting a viewer) and by the
tests. Reads with ``rerun.chunk.RrdReader`` (Rerun >= 0.41), which streams the file's chunks.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

#: Rerun's bookkeeping entities, left out of :attr:`RecordingSummary.entity_paths`.
_INTERNAL_PREFIXES = ("__properties",)


@dataclass
class RecordingSummary:
    """What one recording in an ``.rrd`` file contains.

    Attributes:
        path: the file; ``size_bytes``: its size.
        application_id, recording_id: Rerun's identifiers of the recording.
        entity_paths: every entity with data, without the leading ``/`` (``world/cloud``).
        static_paths: entities with static data (logged once, outside any timeline).
        times: timeline name -> entity path -> sorted times of that entity's rows on it
            (seconds for durations such as ``sim_time``, raw integers for sequences).
        texts: entity path -> the latest text logged there (``TextDocument`` / ``TextLog``) on
            the timeline ``text_key`` of :func:`read_recording` (static text counts as earliest).
        n_chunks: number of chunks read.
        camera_positions: ``world/cameras/<cam>`` -> its first logged position (metres).
        floor_centre: the middle of the bottom of the ``world/workspace`` box, or None.
    """

    path: Path
    size_bytes: int
    application_id: str
    recording_id: str
    entity_paths: list[str] = field(default_factory=list)
    static_paths: list[str] = field(default_factory=list)
    times: dict[str, dict[str, NDArray[np.float64]]] = field(default_factory=dict)
    texts: dict[str, str] = field(default_factory=dict)
    n_chunks: int = 0
    camera_positions: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    floor_centre: NDArray[np.float64] | None = None

    @property
    def camera_names(self) -> list[str]:
        """The depth cameras' names (``left`` of ``world/cameras/left/depth``), sorted."""
        return sorted(
            p.split("/")[2]
            for p in self.entity_paths
            if re.fullmatch(r"world/cameras/[^/]+/depth", p)
        )

    def timeline(self, name: str) -> NDArray[np.float64]:
        """All distinct times on timeline ``name`` over every entity, sorted (empty if absent)."""
        parts = list(self.times.get(name, {}).values())
        return np.unique(np.concatenate(parts)) if parts else np.zeros(0)


def _index_values(column, arrow_type) -> NDArray[np.float64]:
    import pyarrow as pa

    if pa.types.is_duration(arrow_type):
        unit = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}[arrow_type.unit]
        return column.cast(pa.int64()).to_numpy(zero_copy_only=False) * unit
    if pa.types.is_timestamp(arrow_type):
        return column.cast(pa.int64()).to_numpy(zero_copy_only=False).astype(np.float64) * 1e-9
    return column.to_numpy(zero_copy_only=False).astype(np.float64)


def _read_texts(
    batch, timelines: list[str], text_key: str, entity: str, latest: dict[str, tuple[float, str]]
) -> None:
    """Keep in ``latest`` the text of ``entity`` logged last on ``text_key`` (static: earliest)."""
    for text_col in ("TextDocument:text", "TextLog:text"):
        if text_col not in batch.schema.names:
            continue
        when = (
            _index_values(batch.column(text_key), batch.schema.field(text_key).type)
            if text_key in timelines
            else np.full(batch.num_rows, -np.inf)
        )
        for t, value in zip(when, batch.column(text_col).to_pylist(), strict=True):
            text = value[-1] if isinstance(value, list) and value else value
            if text and t >= latest.get(entity, (-np.inf, ""))[0]:
                latest[entity] = (float(t), str(text))


def _read_geometry(summary: RecordingSummary, entity: str, batch) -> None:
    """Note the first camera positions and the workspace box (for the default view)."""
    names = batch.schema.names
    if re.fullmatch(r"world/cameras/[^/]+", entity) and "Transform3D:translation" in names:
        if entity not in summary.camera_positions:
            first = batch.column("Transform3D:translation").to_pylist()[0]
            summary.camera_positions[entity] = np.asarray(first, dtype=float).reshape(3)
    elif entity == "world/workspace" and {"Boxes3D:centers", "Boxes3D:half_sizes"} <= set(names):
        centre = np.asarray(batch.column("Boxes3D:centers").to_pylist()[0], float).reshape(3)
        half = np.asarray(batch.column("Boxes3D:half_sizes").to_pylist()[0], float).reshape(3)
        summary.floor_centre = centre - np.array([0.0, 0.0, half[2]])


def read_recording(path: str | Path, text_key: str = "sim_time") -> RecordingSummary:
    """Summarise the first recording of an ``.rrd`` file.

    Raises:
        FileNotFoundError: no such file.
        ValueError: not an ``.rrd`` file, or one Rerun cannot read, or one without a recording.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(
            f"no such recording: {p} (record one with `hsqbench trial --object NAME --rerun {p}`)"
        )
    if p.is_dir():
        raise ValueError(f"{p} is a directory; give the path of one .rrd file")
    if p.suffix != ".rrd":
        raise ValueError(f"{p} is not a Rerun recording: the name must end in .rrd")
    from rerun.chunk import RrdReader

    try:
        reader = RrdReader(p)
        stores = reader.recordings()
    except Exception as exc:  # the reader raises its own error types; name the file in ours
        raise ValueError(f"Rerun cannot read {p}: {exc}") from None
    if not stores:
        raise ValueError(f"{p} holds no recording (an empty or blueprint-only .rrd file)")
    entry = stores[0]
    summary = RecordingSummary(
        path=p,
        size_bytes=p.stat().st_size,
        application_id=str(entry.application_id),
        recording_id=str(entry.recording_id),
    )
    entities: set[str] = set()
    static: set[str] = set()
    times: dict[str, dict[str, list[NDArray[np.float64]]]] = {}
    latest: dict[str, tuple[float, str]] = {}
    try:
        for chunk in reader.stream(store=entry):
            summary.n_chunks += 1
            entity = chunk.entity_path.lstrip("/")
            if entity.startswith(_INTERNAL_PREFIXES) or chunk.is_empty:
                continue
            entities.add(entity)
            batch = chunk.to_record_batch()
            if chunk.is_static:
                static.add(entity)
            _read_geometry(summary, entity, batch)
            for name in chunk.timeline_names:
                column = batch.column(name)
                per = times.setdefault(name, {}).setdefault(entity, [])
                per.append(_index_values(column, batch.schema.field(name).type))
            _read_texts(batch, chunk.timeline_names, text_key, entity, latest)
    except Exception as exc:
        raise ValueError(f"Rerun cannot read {p} (a truncated or corrupt file?): {exc}") from None
    summary.texts = {e: text for e, (_, text) in latest.items()}
    summary.entity_paths = sorted(entities)
    summary.static_paths = sorted(static)
    summary.times = {
        tl: {e: np.sort(np.concatenate(v)) for e, v in per.items()} for tl, per in times.items()
    }
    return summary
