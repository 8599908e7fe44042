"""The object library: every object the benchmark can place, by name.

Sources: ``ycb`` (the YCB objects in ``HSQ_YCB_DIR``, any number, or those downloaded into the
data folder: :mod:`hsqbench.assets.on_demand`), ``procedural`` (built-in shapes named
``proc_*``, always available) and ``imported`` (meshes registered with ``hsqbench assets
import``). ``get_object`` builds an object once (convex decomposition, mass properties, MuJoCo
meshes) and afterwards loads it from the cache (``hsqbench.settings.cache_dir()``).

The YCB Object and Model Set is licensed CC BY 4.0 (Calli et al., "Benchmarking in Manipulation
Research: The YCB Object and Model Set and Benchmarking Protocols", IEEE RAM 2015): results and
images made with it must credit it.
"""

from __future__ import annotations

import sys
import warnings
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from functools import cache
from multiprocessing import get_context
from pathlib import Path

from hsqbench.assets.asset import SOURCES, ObjectAsset
from hsqbench.assets.build import AssetError, AssetWarning, ObjectSpec, build_object, load_cached
from hsqbench.assets.config import AssetsConfig, load_assets_config
from hsqbench.assets.importer import imported_specs
from hsqbench.assets.ycb import ycb_entries
from hsqbench.settings import cache_dir, ycb_dir_is_set

__all__ = [
    "AssetError",
    "AssetWarning",
    "BuildReport",
    "ObjectAsset",
    "UnknownObjectError",
    "build_objects",
    "default_config",
    "get_object",
    "is_built",
    "object_names",
    "object_spec",
    "prepare_objects",
    "ycb_names",
]


class UnknownObjectError(ValueError):
    """No object of that name; the message lists the known ones."""


@cache
def default_config() -> AssetsConfig:
    """``configs/assets.yaml``, read once per process."""
    return load_assets_config()


def ycb_names() -> list[str]:
    """The YCB library: the objects of ``HSQ_YCB_DIR`` in ``objects.csv`` order or, when it is
    unset, every object hsqbench downloads on demand (``download.objects`` of
    ``configs/assets.yaml``, the order the download folder's ``objects.csv`` keeps)."""
    if not ycb_dir_is_set():
        return [o.name for o in default_config().download.objects]
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
    if any(o.name == name for o in config.download.objects):
        if ycb_dir_is_set():
            hint = (
                f" {name!r} is a YCB object that HSQ_YCB_DIR does not hold (see its "
                "objects.csv); add it there, or unset HSQ_YCB_DIR to let hsqbench download it"
            )
        else:
            hint = (
                f" {name!r} is a YCB object not downloaded yet: `hsqbench assets download "
                f"{name}` fetches it (a benchmark that uses it does so by itself)"
            )
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


BUILD_DIED = (
    "the build process died (a crash in CoACD or MuJoCo, or out of memory); it was built again "
    "alone and died again"
)


@dataclass
class BuildReport:
    """What :func:`prepare_objects` made ready: ``assets`` by name, in the order asked, and the
    objects that ``failed`` with the reason, in one line each."""

    assets: dict[str, ObjectAsset] = field(default_factory=dict)
    failed: dict[str, str] = field(default_factory=dict)


def _reason(exc: BaseException) -> str:
    text = " | ".join(line.strip() for line in str(exc).splitlines() if line.strip())
    return f"{type(exc).__name__}: {text}"


Builder = Callable[[ObjectSpec, AssetsConfig, Path], tuple[ObjectAsset, list[str]]]


def _pool_pass(
    specs: list[ObjectSpec], config: AssetsConfig, root: Path, jobs: int, build: Builder
) -> Iterator[tuple[str, ObjectAsset | None, str | None, list[str]]]:
    """Build ``specs`` in one pool of ``jobs`` processes; yields (name, asset, error, warnings)
    as they finish, error ``None`` on success. Objects lost to a dead worker are yielded last
    with the error ``BUILD_DIED`` (their build may not have started)."""
    lost: list[str] = []
    with ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("spawn")) as pool:
        futures = {pool.submit(build, s, config, root): s.name for s in specs}
        for future in as_completed(futures):
            name = futures[future]
            try:
                asset, messages = future.result()
            except BrokenProcessPool:
                lost.append(name)
                continue
            except Exception as exc:
                yield name, None, _reason(exc), []
                continue
            yield name, asset, None, messages
    for name in lost:
        yield name, None, BUILD_DIED, []


def _builds(
    specs: list[ObjectSpec],
    config: AssetsConfig,
    root: Path,
    jobs: int,
    build: Builder = _build_one,
) -> Iterator[tuple[str, ObjectAsset | None, str | None, list[str]]]:
    """(name, asset, error, warnings) of each spec as it is built (``build``: a picklable
    function, so that tests can make a worker die)."""
    if jobs == 1:
        for spec in specs:
            try:
                asset, messages = build(spec, config, root)
            except Exception as exc:
                yield spec.name, None, _reason(exc), []
                continue
            yield spec.name, asset, None, messages
        return
    lost = []
    for name, asset, error, messages in _pool_pass(specs, config, root, jobs, build):
        if error == BUILD_DIED:
            lost.append(name)
        else:
            yield name, asset, error, messages
    by_name = {s.name: s for s in specs}
    for name in lost:  # one at a time, so the object that kills its process is the one blamed
        yield from _pool_pass([by_name[name]], config, root, 1, build)


def prepare_objects(
    names: Iterable[str],
    jobs: int | None = None,
    config: AssetsConfig | None = None,
    progress: bool = True,
) -> BuildReport:
    """Load from the cache, or build, each object of ``names``; ``jobs`` builds at a time in
    separate processes. An object that cannot be built (unreadable mesh, no hulls, MuJoCo rejects
    it, its build process crashes) is reported in ``BuildReport.failed`` with the reason, and the
    others are still built: one bad mesh never stops the rest.

    Progress goes to stderr: a bar on a terminal, one line per object built otherwise.

    Raises:
        UnknownObjectError: a name is not in the library (a typo, or YCB meshes missing): no
            object is built.
    """
    config = config or default_config()
    names = list(dict.fromkeys(names))
    specs = [object_spec(n, config) for n in names]
    root = cache_dir()
    ready: dict[str, ObjectAsset] = {}
    todo = []
    for spec in specs:
        cached = load_cached(spec, config, root)
        if cached is None:
            todo.append(spec)
        else:
            ready[spec.name] = cached
    report = BuildReport()
    shown = _BuildProgress(len(todo), progress)
    jobs = max(1, min(jobs or config.jobs, len(todo) or 1))
    try:
        for name, asset, error, messages in _builds(todo, config, root, jobs):
            for message in messages:
                warnings.warn(message, AssetWarning, stacklevel=2)
            if asset is None:
                report.failed[name] = error or "unknown error"
            else:
                ready[name] = asset
            shown.update(name, asset, error)
    finally:
        shown.close()
    report.assets = {n: ready[n] for n in names if n in ready}
    return report


class _BuildProgress:
    """A bar on a terminal; in a log, one line per object (a bar there is one line per update)."""

    def __init__(self, total: int, enabled: bool) -> None:
        self.total, self.done, self.enabled = total, 0, enabled and total > 0
        self.bar = None
        if self.enabled and sys.stderr.isatty():
            from tqdm import tqdm

            self.bar = tqdm(total=total, desc="building objects", unit="obj")

    def update(self, name: str, asset: ObjectAsset | None, error: str | None) -> None:
        self.done += 1
        if self.bar is not None:
            self.bar.set_postfix_str(name)
            self.bar.update()
        elif self.enabled:
            what = (
                f"built {name} in {asset.info.get('build_s', 0):.1f} s"
                if asset is not None
                else f"cannot build {name}: {error}"
            )
            print(f"objects {self.done}/{self.total}: {what}", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def build_objects(
    names: Iterable[str] | None = None,
    jobs: int | None = None,
    config: AssetsConfig | None = None,
    progress: bool = True,
) -> list[ObjectAsset]:
    """Build ``names`` (default: all known objects), ``jobs`` at a time in separate processes.

    Objects already in the cache are loaded, not rebuilt. Fallback warnings raised in worker
    processes are re-issued here as ``AssetWarning``. Returns the assets in the order of ``names``.

    Raises:
        AssetError: some objects cannot be built (all are tried first; the message names each
            with its reason). Use :func:`prepare_objects` to get the others anyway.
    """
    config = config or default_config()
    names = list(object_names(config=config) if names is None else names)
    report = prepare_objects(names, jobs=jobs, config=config, progress=progress)
    if report.failed:
        raise AssetError(failure_message(report.failed))
    return [report.assets[n] for n in names]


def failure_message(failed: dict[str, str]) -> str:
    """``N object(s) cannot be built:`` then one ``  name: reason`` line each."""
    lines = [f"{len(failed)} object(s) cannot be built:"]
    lines += [f"  {name}: {why}" for name, why in failed.items()]
    return "\n".join(lines)
