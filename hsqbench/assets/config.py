"""Object-library configuration: ``configs/assets.yaml`` loaded into typed, frozen dataclasses.

Every default here is mirrored, with its reason, in ``configs/assets.yaml``. Lengths are metres,
masses kilograms, densities kg/m^3.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from hsqbench.config import load_config


@dataclass(frozen=True)
class CoacdConfig:
    """Parameters of the CoACD convex decomposition (names as in ``coacd.run_coacd``).

    ``pre_simplify_faces``: the cleaned mesh is reduced to at most this many faces (quadric
    decimation) before CoACD, which is the slow step; 0 disables it.
    """

    threshold: float = 0.08
    max_convex_hull: int = 16
    preprocess_mode: str = "auto"
    preprocess_resolution: int = 40
    resolution: int = 2000
    mcts_nodes: int = 20
    mcts_iterations: int = 60
    mcts_max_depth: int = 3
    decimate: bool = True
    max_ch_vertex: int = 128
    seed: int = 0
    pre_simplify_faces: int = 3000

    def __post_init__(self) -> None:
        if not 0.0 < self.threshold < 1.0:
            raise ValueError(f"coacd.threshold must be in (0, 1), got {self.threshold}")
        if self.max_convex_hull == 0 or self.max_convex_hull < -1:
            raise ValueError("coacd.max_convex_hull must be -1 (no limit) or >= 1")
        if self.preprocess_mode not in ("auto", "on", "off"):
            raise ValueError(
                f"coacd.preprocess_mode must be auto, on or off, got {self.preprocess_mode!r}"
            )
        if self.pre_simplify_faces < 0:
            raise ValueError("coacd.pre_simplify_faces must be >= 0 (0 disables it)")


@dataclass(frozen=True)
class HullConfig:
    """Clean-up of the convex hulls so MuJoCo accepts every one of them.

    A hull whose volume is below ``min_volume_fraction`` of the summed hull volume, or below
    ``min_volume_m3``, is merged into the nearest other hull (by centroid distance).
    """

    min_volume_fraction: float = 0.005
    min_volume_m3: float = 1.0e-8

    def __post_init__(self) -> None:
        if not 0.0 <= self.min_volume_fraction < 1.0:
            raise ValueError("hulls.min_volume_fraction must be in [0, 1)")
        if self.min_volume_m3 < 0.0:
            raise ValueError("hulls.min_volume_m3 must be >= 0")


@dataclass(frozen=True)
class VisualConfig:
    """The visual mesh written next to the hulls."""

    max_faces: int = 20000

    def __post_init__(self) -> None:
        if self.max_faces < 100:
            raise ValueError("visual.max_faces must be >= 100")


@dataclass(frozen=True)
class YcbObject:
    """One entry of the YCB table used by ``hsqbench assets download``."""

    name: str
    ycb_id: str
    mass_kg: float


@dataclass(frozen=True)
class DownloadConfig:
    """Where ``hsqbench assets download`` fetches the Google 16k YCB scans from.

    ``base_url``: archives are ``{base_url}/{ycb_id}_{name}_google_16k.tgz``.
    ``sha256``: optional ``name -> hex digest`` of each archive, checked when given.
    """

    base_url: str = "http://ycb-benchmarks.s3-website-us-east-1.amazonaws.com/data/google"
    timeout_s: float = 60.0
    min_archive_bytes: int = 10000
    chunk_bytes: int = 262144
    sha256: dict[str, str] = field(default_factory=dict)
    objects: tuple[YcbObject, ...] = ()


@dataclass(frozen=True)
class ImportConfig:
    """Defaults of ``hsqbench assets import``."""

    density_kg_m3: float = 500.0
    rgba: tuple[float, float, float, float] = (0.7, 0.7, 0.7, 1.0)

    def __post_init__(self) -> None:
        if self.density_kg_m3 <= 0.0:
            raise ValueError("importer.density_kg_m3 must be > 0")


@dataclass(frozen=True)
class ProceduralObject:
    """One built-in procedural object. ``kind`` picks the generator; ``size_m`` its dimensions.

    kinds and ``size_m``: box (x, y, z); cylinder (radius, height); sphere (radius,);
    l (arm length x, arm length y, arm width, height); mug (outer radius, height, wall,
    handle radius, handle width).
    """

    name: str
    kind: str
    size_m: tuple[float, ...]
    rgba: tuple[float, float, float, float] = (0.7, 0.7, 0.7, 1.0)


@dataclass(frozen=True)
class ProceduralConfig:
    density_kg_m3: float = 400.0
    sections: int = 48
    objects: tuple[ProceduralObject, ...] = ()


@dataclass(frozen=True)
class AssetsConfig:
    coacd: CoacdConfig = field(default_factory=CoacdConfig)
    hulls: HullConfig = field(default_factory=HullConfig)
    visual: VisualConfig = field(default_factory=VisualConfig)
    download: DownloadConfig = field(default_factory=DownloadConfig)
    importer: ImportConfig = field(default_factory=ImportConfig)
    procedural: ProceduralConfig = field(default_factory=ProceduralConfig)
    jobs: int = 2

    def __post_init__(self) -> None:
        if self.jobs < 1:
            raise ValueError("jobs must be >= 1")


def load_assets_config(path: str | Path | None = "assets") -> AssetsConfig:
    """Load ``configs/assets.yaml`` (or another file); ``None`` gives the built-in defaults."""
    return load_config(AssetsConfig, path)
