"""The object library: every object the benchmark can place, by name.

Sources: ``ycb`` (the 15 YCB objects in ``HSQ_YCB_DIR``), ``procedural`` (built-in shapes named
``proc_*``, always available) and ``imported`` (meshes registered with ``hsqbench assets
import``). ``get_object`` builds an object once (convex decomposition, mass properties, MuJoCo
meshes) and afterwards loads it from the cache (``hsqbench.settings.cache_dir()``).

The YCB Object and Model Set is licensed CC BY 4.0 (Calli et al., "Benchmarking in Manipulation
Research: The YCB Object and Model Set and Benchmarking Protocols", IEEE RAM 2015): results and
images made with it must credit it.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable
from concurrent.futures import ProcessPoolExecutor, as_completed
from functools import cache
from multiprocessing import get_context
from pathlib import Path

from hsqbench.assets.asset import SOURCES, ObjectAsset
from hsqbench.assets.build import AssetError, AssetWarning, ObjectSpec, build_object, load_cached
from hsqbench.assets.config import AssetsConfig, load_assets_config
from hsqbench.assets.importer import imported_specs
from hsqbench.assets.ycb import ycb_entries
from hsqbench.settings import cache_dir, ycb_dir

__all__ = [
    "AssetError",
    "AssetWarning",
    "ObjectAsset",
    "UnknownObjectError",
    "build_objects",
    "default_config",
    "get_object",
    "is_built",
    "object_names",
    "object_spec",
    "ycb_names",
]


class UnknownObjectError(ValueError):
    """No object of that name; the message lists the known ones."""


@cache
def default_config() -> AssetsConfig:
    """``configs/assets.yaml``, read once per process."""
    return load_assets_config()


def ycb_names() -> list[str]:
    """The YCB object names of ``HSQ_YCB_DIR`` in ``objects.csv`` order.

    Raises:
        hsqbench.settings.SettingError: ``HSQ_YCB_DIR`` is unset; the message says how to get the meshes.
    """
    return [e.name for e in ycb_entries(required=True)]


def _specs(config: AssetsConfig, source: str | None = None) -> dict[str, ObjectSpec]:
    specs: dict[str, ObjectSpec] = {}
    if source in (None, "ycb"):
        for e in ycb_entries(required=False):
            specs[e.name] = ObjectSpec(
                name=e.name, source="ycb", mesh_path=e.mesh_path, mass_kg=e.mass_kg
            )
    if source in (None, "procedural"):
        proc = config.procedural
        for obj in proc.objects:
            specs[obj.name] = ObjectSpec(
                name=obj.name,
                source="procedural",
                density_kg_m3=proc.density_kg_m3,
                rgba=obj.rgba,
                procedural=obj,
                sections=proc.sections,
            )
    if source in (None, "imported"):
        for name, spec in imported_specs(cache_dir()).items():
            specs.setdefault(name, spec)
    return specs


def object_names(source: str | None = None, config: AssetsConfig | None = None) -> list[str]:
    """All known object names: YCB (if ``HSQ_YCB_DIR`` is set), procedural, then imported.

    ``source`` restricts to one of ``"ycb"``, ``"procedural"``, ``"imported"``.
    """
    if source is not None and source not in SOURCES:
        raise ValueError(f"unknown source {source!r}; known: {list(SOURCES)}")
    return list(_specs(config or default_config(), source))


def object_spec(name: str, config: AssetsConfig | None = None) -> ObjectSpec:
    """The build specification of ``name``; an unknown name lists the known ones."""
    config = config or default_config()
    specs = _specs(config)
    if name in specs:
        return specs[name]
    hint = ""
    if ycb_dir(required=False) is None and any(o.name == name for o in config.download.objects):
        try:
            ycb_dir(required=True)
        except Exception as exc:  # its message says how to get the YCB meshes
            hint = f" {name!r} is a YCB object, but {exc}"
    raise UnknownObjectError(f"unknown object {name!r}; known objects: {', '.join(specs)}.{hint}")


def is_built(name: str, config: AssetsConfig | None = None) -> bool:
    """Whether ``name`` is in the cache for the current inputs and parameters."""
    config = config or default_config()
    return load_cached(object_spec(name, config), config, cache_dir()) is not None


def get_object(name: str, build: bool = True, config: AssetsConfig | None = None) -> ObjectAsset:
    """The built object ``name``: from the cache, else built now (unless ``build`` is False).

    Raises:
        UnknownObjectError: no such object (the message lists the known ones).
        FileNotFoundError: ``build`` is False and the object is not built yet.
        AssetError: the mesh cannot be read or built (the message names the file).
    """
    config = config or default_config()
    spec = object_spec(name, config)
    cached = load_cached(spec, config, cache_dir())
    if cached is not None:
        return cached
    if not build:
        raise FileNotFoundError(
            f"object {name!r} is not built for the current inputs; run `hsqbench assets build {name}`"
        )
    return build_object(spec, config, cache_dir())


def _build_one(spec: ObjectSpec, config: AssetsConfig, root: Path) -> tuple[ObjectAsset, list[str]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", AssetWarning)
        asset = build_object(spec, config, root)
    return asset, [str(w.message) for w in caught if issubclass(w.category, AssetWarning)]


def build_objects(
    names: Iterable[str] | None = None,
    jobs: int | None = None,
    config: AssetsConfig | None = None,
    progress: bool = True,
) -> list[ObjectAsset]:
    """Build ``names`` (default: all known objects), ``jobs`` at a time in separate processes.

    Objects already in the cache are loaded, not rebuilt. Fallback warnings raised in worker
    processes are re-issued here as ``AssetWarning``. Returns the assets in the order of ``names``.
    """
    from tqdm import tqdm

    config = config or default_config()
    names = list(object_names(config=config) if names is None else names)
    specs = [object_spec(n, config) for n in names]
    root = cache_dir()
    jobs = max(1, min(jobs or config.jobs, len(specs) or 1))
    results: dict[str, ObjectAsset] = {}
    bar = tqdm(total=len(specs), desc="building objects", unit="obj", disable=not progress)
    try:
        if jobs == 1:
            for spec in specs:
                results[spec.name], messages = _build_one(spec, config, root)
                for message in messages:
                    warnings.warn(message, AssetWarning, stacklevel=2)
                bar.update()
        else:
            with ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("spawn")) as pool:
                futures = {pool.submit(_build_one, s, config, root): s.name for s in specs}
                for future in as_completed(futures):
                    results[futures[future]], messages = future.result()
                    for message in messages:
                        warnings.warn(message, AssetWarning, stacklevel=2)
                    bar.set_postfix_str(futures[future])
                    bar.update()
    finally:
        bar.close()
    return [results[n] for n in names]
