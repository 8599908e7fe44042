"""The report's note on scenes that were still moving when the cameras first looked (the
``scene_max_speed`` column against the run's ``physics.settle_speed_mps``)."""

from __future__ import annotations

from typing import Any

import pandas as pd


def unsettled_note(attempts: pd.DataFrame, meta: dict[str, Any]) -> str | None:
    """How many of the run's scenes (one per trial) ended their settling above the rest speed,
    with the largest speed; ``None`` when none did, or when the run predates the column."""
    if "scene_max_speed" not in attempts or not len(attempts):
        return None
    backend = meta.get("backend", {})
    physics = backend.get("trial_config", {}).get("physics", {})
    if isinstance(physics, str):  # older runs name the file; its settings are under configs
        physics = backend.get("configs", {}).get("physics", {})
    limit = physics.get("settle_speed_mps")
    speeds = pd.to_numeric(
        attempts.drop_duplicates("trial_key")["scene_max_speed"], errors="coerce"
    ).dropna()
    if limit is None or speeds.empty:
        return None
    moving = speeds[speeds >= float(limit)]
    if moving.empty:
        return None
    return (
        f"{len(moving)} of {len(speeds)} scenes were still moving when the cameras first looked "
        f"(largest object speed {moving.max():.3f} m/s or rad/s, at rest below {limit}; "
        "scene_max_speed in attempts.csv names them)"
    )
