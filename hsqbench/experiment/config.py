"""Benchmark protocol: a file of ``configs/protocols/`` (``paper.yaml``, ``quick.yaml``, ...)
loaded into frozen dataclasses (docs/protocols.md lists them).

An :class:`ExperimentConfig` says *what* is run (objects, attempts, rounds, planners, seeds);
*how* one trial runs (scene, robot, stop rule of a packed round) belongs to the trial runner's
own config, named here by ``trial_config`` and loaded by the simulation backend.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

from hsqbench.config import from_dict, load_config_data, resolve_config_path
from hsqbench.errors import ConfigError

EXPERIMENTS = ("isolated", "packed", "pile")
#: Experiments run as clutter-removal rounds (one record per round in ``rounds.csv``).
ROUND_EXPERIMENTS = ("packed", "pile")

# The paper's 15 objects (YCB ids 003-077); the same names as ``HSQ_YCB_DIR/objects.csv``.
YCB_OBJECTS = (
    "cracker_box",
    "sugar_box",
    "tomato_soup_can",
    "mustard_bottle",
    "potted_meat_can",
    "banana",
    "apple",
    "bleach_cleanser",
    "bowl",
    "mug",
    "power_drill",
    "phillips_screwdriver",
    "hammer",
    "foam_brick",
    "rubiks_cube",
)


ALL = "all"


def resolve_objects(
    objects: tuple[str, ...] | str, exclude: tuple[str, ...], where: str
) -> tuple[str, ...]:
    """``objects`` as names: ``"all"`` is every YCB object of ``HSQ_YCB_DIR`` (``objects.csv``
    order), so a user with a larger YCB download runs all of theirs; ``exclude`` is then taken out.

    Raises:
        ConfigError: another string than ``all``, or an excluded name the list does not hold (a
            typo would otherwise let an object slip into the protocol).
    """
    if isinstance(objects, str):
        if objects != ALL:
            raise ConfigError(f"{where}: a list of names or {ALL!r}, got {objects!r}")
        from hsqbench.assets.library import ycb_names

        objects = tuple(ycb_names())
    unknown = sorted(set(exclude) - set(objects))
    if unknown:
        raise ConfigError(f"{where}: exclude names {unknown}, which are not among the objects")
    return tuple(o for o in objects if o not in exclude)


def _check_objects(objects: tuple[str, ...], where: str) -> None:
    if not objects:
        raise ConfigError(f"{where}: the object list is empty")
    bad = [o for o in objects if not o.strip() or any(c in o for c in "/;,")]
    if bad:
        raise ConfigError(f"{where}: object names must be non-empty without '/', ';' or ',': {bad}")
    dupes = sorted({o for o in objects if objects.count(o) > 1})
    if dupes:
        raise ConfigError(f"{where}: duplicate object(s) {dupes}")


@dataclass(frozen=True)
class IsolatedConfig:
    """Isolated scenes: each object alone, ``attempts_per_object`` independent attempts.

    Attributes:
        enabled: run this experiment at all.
        objects: object names, as the trial runner knows them, or ``"all"`` (every YCB object
            of ``HSQ_YCB_DIR``); resolved to names when the config is made.
        exclude: names taken out of ``objects`` (the paper's 15, for the unseen-object protocol).
        attempts_per_object: trials per object and base seed, each at its own random pose.
    """

    enabled: bool = True
    objects: tuple[str, ...] | str = YCB_OBJECTS
    exclude: tuple[str, ...] = ()
    attempts_per_object: int = 10

    def __post_init__(self) -> None:
        names = resolve_objects(self.objects, self.exclude, "isolated.objects")
        object.__setattr__(self, "objects", names)
        _check_objects(self.objects, "isolated.objects")
        if self.attempts_per_object < 1:
            raise ConfigError(
                f"isolated.attempts_per_object must be >= 1, got {self.attempts_per_object}"
            )


@dataclass(frozen=True)
class PackedConfig:
    """Packed scenes: ``rounds`` rounds, each of ``objects_per_round`` objects drawn from ``objects``.

    A round is run whole by the trial runner (it stops when the table is empty or after two
    consecutive failed attempts, the paper's rule). ``objects`` and ``exclude`` as for
    :class:`IsolatedConfig`. A draw whose objects cannot be placed apart
    is replaced by the next draw of the same round's stream, up to ``max_draws`` draws (see
    :func:`hsqbench.experiment.seeds.draw_packed_round`).
    """

    enabled: bool = True
    objects: tuple[str, ...] | str = YCB_OBJECTS
    exclude: tuple[str, ...] = ()
    rounds: int = 15
    objects_per_round: int = 5
    max_draws: int = 10

    #: The config section's name, for messages.
    SECTION = "packed"

    def __post_init__(self) -> None:
        where = self.SECTION
        names = resolve_objects(self.objects, self.exclude, f"{where}.objects")
        object.__setattr__(self, "objects", names)
        _check_objects(self.objects, f"{where}.objects")
        if self.rounds < 1:
            raise ConfigError(f"{where}.rounds must be >= 1, got {self.rounds}")
        if not 1 <= self.objects_per_round <= len(self.objects):
            raise ConfigError(
                f"{where}.objects_per_round must be between 1 and the {len(self.objects)} "
                f"objects of {where}.objects, got {self.objects_per_round}"
            )
        if self.max_draws < 1:
            raise ConfigError(f"{where}.max_draws must be >= 1, got {self.max_draws}")


@dataclass(frozen=True)
class PileConfig(PackedConfig):
    """Pile scenes (VGN/GIGA's clutter protocol; Table IV): rounds as packed ones, but the
    objects are dropped into a heap (:mod:`hsqbench.sim.scene.pile`) and touch each other.

    **Off unless a config enables it** (``enabled: false`` by default): the paper has no pile
    experiment, so ``paper.yaml`` leaves it out and ``paper_pile.yaml`` adds it. Same fields
    and the same stop rule as packed rounds; a draw whose pile does not settle on the table in
    the workspace is replaced by the round's next draw, up to ``max_draws``.
    """

    enabled: bool = False
    SECTION = "pile"


@dataclass(frozen=True)
class ExperimentConfig:
    """One benchmark protocol.

    Attributes:
        planners: planner names, resolved by the trial runner (``hsqbench.planner.registry.get_planner``).
        seeds: base seeds. Every trial's seed derives from (base seed, experiment, object, index)
            (see :mod:`hsqbench.experiment.seeds`); more base seeds repeat the whole protocol on
            fresh poses and narrow the confidence intervals.
        trial_config: name (in ``configs/``) or path of the trial runner's config.
        confidence: level of the Wilson intervals in the report, in (0, 1).
        isolated, packed: the two experiments of the paper.
        pile: objects heaped and touching (VGN/GIGA's pile scenes), off by default.
    """

    planners: tuple[str, ...] = ("hsq", "single-sq", "antipodal")
    seeds: tuple[int, ...] = (0,)
    trial_config: str = "trial"
    confidence: float = 0.95
    isolated: IsolatedConfig = field(default_factory=IsolatedConfig)
    packed: PackedConfig = field(default_factory=PackedConfig)
    pile: PileConfig = field(default_factory=PileConfig)

    def __post_init__(self) -> None:
        if not self.planners:
            raise ConfigError("planners: list at least one planner")
        dupes = sorted({p for p in self.planners if self.planners.count(p) > 1})
        if dupes:
            raise ConfigError(f"planners: duplicate planner(s) {dupes}")
        bad = [p for p in self.planners if not p or "/" in p or "," in p or ";" in p]
        if bad:
            raise ConfigError(f"planners: names must be non-empty without '/', ',' or ';': {bad}")
        if not self.seeds:
            raise ConfigError("seeds: list at least one base seed, e.g. [0]")
        if any(s < 0 for s in self.seeds) or len(set(self.seeds)) != len(self.seeds):
            raise ConfigError(f"seeds: must be distinct non-negative integers, got {self.seeds}")
        if not 0.0 < self.confidence < 1.0:
            raise ConfigError(f"confidence must be in (0, 1), got {self.confidence}")
        if not self.enabled_experiments():
            raise ConfigError(
                f"every experiment is disabled: enable one of {list(EXPERIMENTS)} "
                "(e.g. isolated: {enabled: true})"
            )

    def enabled_experiments(self) -> tuple[str, ...]:
        return tuple(e for e in EXPERIMENTS if getattr(self, e).enabled)

    def object_names(self) -> tuple[str, ...]:
        """Every object the enabled experiments use, each once, in first-use order (what a run
        must build before it starts)."""
        names: dict[str, None] = {}
        for e in self.enabled_experiments():
            names.update(dict.fromkeys(getattr(self, e).objects))
        return tuple(names)


#: Top-level keys whose default a protocol file should state; left out, the loader says which
#: default it took (they decide which methods run and how often).
_STATED_DEFAULTS = ("planners", "seeds")


def load_experiment_config(name_or_path: str | Path = "paper") -> ExperimentConfig:
    """Load ``configs/<name>.yaml`` (``paper``, ``quick``) or a YAML path (``extends:`` applied).

    A protocol runs the experiments it names: a section (``isolated``, ``packed``, ``pile``)
    that the file (with its ``extends:`` chain) leaves out is off, never the paper's default.
    ``planners`` or ``seeds`` left out take their defaults, and a line on stderr says so.

    Raises:
        ConfigError: the file names no experiment, or a value is invalid.
    """
    path = resolve_config_path(name_or_path)
    data = load_config_data(path)
    if not any(e in data for e in EXPERIMENTS):
        from_dict(ExperimentConfig, data, where=path.name)  # a wrong value is named first
        raise ConfigError(
            f"{path.name} names no experiment: add a section for one of {list(EXPERIMENTS)}, "
            "e.g. isolated: {objects: [mug], attempts_per_object: 1}"
        )
    for e in EXPERIMENTS:
        data.setdefault(e, {"enabled": False})
    taken = [f"{k} {list(getattr(ExperimentConfig, k))}" for k in _STATED_DEFAULTS if k not in data]
    if taken:
        print(f"{path.name}: not stated, default taken: {'; '.join(taken)}", file=sys.stderr)
    return from_dict(ExperimentConfig, data, where=path.name)
