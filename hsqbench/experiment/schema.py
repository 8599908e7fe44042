"""The columns of a run's results files, once: name, kind, units and meaning of every column of
``attempts.csv`` and ``rounds.csv``.

The writer formats each field by its column's kind and every reader types each column by it
(:mod:`hsqbench.experiment.csv_fields`), and docs/results-format.md's column tables are rendered
from here (:mod:`hsqbench.experiment.schema_doc`).

Dtypes are NumPy's, with NaN for an empty field, as ``pd.read_csv`` reads the files: a number
column that may be empty (an error row, an older run) is ``float64`` even when its values are
whole numbers, since only NaN behaves alike in masks, sums and means under pandas 2.2 and 3.x;
``int64`` columns are the trial's identity, filled on every row of every version. Text stays
text, ``""`` where empty (``str`` under pandas 3, ``object`` before).
"""

from __future__ import annotations

from dataclasses import dataclass

from hsqbench.sim.outcome import Outcome

#: kind -> (pandas dtype, what an empty field is).
KINDS: dict[str, tuple[str, str]] = {
    "int": ("int64", "never empty"),
    "count": ("float64", "NaN where empty"),  # whole numbers, absent on some rows
    "float": ("float64", "NaN where empty"),
    "bool": ("float64", "1.0 / 0.0, NaN where empty"),
    "text": ("str", '"" where empty'),
}


class SchemaError(ValueError):
    """A field that does not hold what its column's kind says (a damaged or edited file)."""


@dataclass(frozen=True)
class Column:
    """One column: ``values`` is the doc's "units / values" cell (units in the name: ``_s``,
    ``_m``)."""

    name: str
    kind: str
    values: str
    meaning: str

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"column {self.name}: kind {self.kind!r} is not one of {list(KINDS)}")

    @property
    def dtype(self) -> str:
        return KINDS[self.kind][0]


POSE = "pose"
_WALL = "s, wall"
_SIM = "s, simulated"

TRIAL_KEY = Column(
    "trial_key",
    "text",
    "text",
    "identity of the trial in the run: `isolated/<planner>/s<base seed>/<object>/<index>`, "
    "`packed/<planner>/s<base seed>/round/<index>`, `pile/...` likewise",
)
PLANNER = Column("planner", "text", "text", "the planner's name")
BASE_SEED = Column("base_seed", "int", "integer", "the protocol's base seed this trial belongs to")
TRIAL_INDEX = Column(
    "trial_index",
    "int",
    "integer",
    "index of the trial (per object for isolated, per round for packed and pile)",
)
SEED = Column(
    "seed", "int", "integer", "the trial's own seed (everything random in the trial comes from it)"
)
OBJECTS = Column("objects", "text", "names joined by `;`", "the objects of the scene")
SCENE_SETTLE_S = Column(
    "scene_settle_s",
    "float",
    _SIM,
    "simulated time the scene took to settle before the cameras looked",
)
SCENE_MAX_SPEED = Column(
    "scene_max_speed",
    "float",
    "m/s or rad/s",
    "largest object speed at the end of settling (above the physics config's "
    "`settle_speed_mps`: still moving)",
)
TRIAL_WALL_S = Column(
    "trial_wall_s",
    "float",
    _WALL,
    "wall time of the whole trial in its worker (the same on every row of a trial)",
)
WORKER = Column("worker", "text", "text", "`host:pid` of the worker process")
CONFIG_HASH = Column(
    "config_hash",
    "text",
    "hex",
    "hash of the run's full config (protocol, trial config tree, named files)",
)
CODE_VERSION = Column(
    "code_version",
    "text",
    "text",
    "`git describe` of the checkout (`-dirty` when modified), else the package version",
)
FINISHED_AT = Column("finished_at", "text", "ISO 8601, UTC", "when the row was written")

FACTOR_NAMES = ("h_alpha", "h_beta", "h_gamma", "h_delta")

#: The last columns of both tables: the scene's settling, the trial's wall time and where and
#: by what code the row was written.
_PROVENANCE: tuple[Column, ...] = (
    SCENE_SETTLE_S,
    SCENE_MAX_SPEED,
    TRIAL_WALL_S,
    WORKER,
    CONFIG_HASH,
    CODE_VERSION,
    FINISHED_AT,
)

ATTEMPTS: tuple[Column, ...] = (
    TRIAL_KEY,
    Column("experiment", "text", "text", "`isolated`, `packed` or `pile`"),
    PLANNER,
    BASE_SEED,
    TRIAL_INDEX,
    SEED,
    OBJECTS,
    Column(
        "attempt_index",
        "int",
        "integer",
        "0-based index of the attempt in its trial; `-1` on the error row of a trial that could "
        "not run",
    ),
    Column("n_attempts", "int", "integer", "attempts of the trial (0 on an error row)"),
    Column(
        "status",
        "text",
        "text",
        "`ok`, or `error` (the trial did not run: an infrastructure error, left out of GSR and "
        "CR; `detail` says why); a planner's own error is `ok` with outcome `planner_error`",
    ),
    Column(
        "outcome",
        "text",
        "text",
        ", ".join(f"`{o}`" for o in Outcome)
        + " (rules: `hsqbench/sim/trial/__init__.py`); empty on an error row. `planner_error`: "
        "the planner raised or broke its contract, a failed attempt in GSR and CR; `detail` "
        "names the planner's file and line",
    ),
    Column("success", "bool", "`1` / `0`", "outcome is `success`"),
    Column(
        "graspable",
        "bool",
        "`1` / `0`",
        "the oracle found a feasible grasp on the true meshes in this presentation (empty: not "
        "checked)",
    ),
    Column(
        "target",
        "text",
        "name",
        "the object grasped, or the one meant (nearest the grasp) for a failure; empty without a "
        "grasp",
    ),
    Column(
        "object_pose",
        "text",
        POSE,
        "settled world pose of `target` when the cameras looked (before the arm moved); for an "
        "isolated trial the only object's, even without a grasp",
    ),
    Column(
        "resting_pose",
        "count",
        "integer",
        "index of that object's drawn resting pose, most probable first; `-1` upright",
    ),
    Column(
        "rank_executed",
        "count",
        "integer",
        "0-based rank, in the planner's list, of the executed grasp; `-1` none executed",
    ),
    Column("n_grasps", "count", "integer", "grasps the planner returned"),
    Column(
        "score",
        "float",
        "planner's units, hsq in [0, 1]",
        "the executed grasp's score (for `unreachable`: the best grasp's)",
    ),
    *(
        Column(
            name,
            "float",
            "[0, 1]",
            "hsq's score factors of that grasp (empty for other planners)",
        )
        for name in FACTOR_NAMES
    ),
    Column(
        "factors", "text", "JSON object", "every score factor the planner reported for that grasp"
    ),
    Column("width_m", "float", "m", "the grasp's planned width between the contacts"),
    Column(
        "grasp_pose",
        "text",
        POSE,
        "world pose of the TCP at the executed grasp, as executed (nudged clear of the table if "
        "it was); for `unreachable`: the planner's best grasp, which no motion reached; empty for "
        "`no_grasp_found`",
    ),
    Column(
        "grasp_flipped",
        "bool",
        "`1` / `0`",
        "the executed grasp is the planner's turned by pi about its approach axis (the same "
        "parallel-jaw grasp, reached with a shorter move)",
    ),
    Column(
        "grasp_pose_object",
        "text",
        POSE,
        "`grasp_pose` in the frame of the object at `object_pose` (where on the object the hand "
        "closed)",
    ),
    Column(
        "top_scores",
        "text",
        "numbers joined by spaces",
        "scores of the planner's first grasps, best first (at most `recorded_scores` of the "
        "trial config, 5)",
    ),
    Column(
        "perception_s",
        "float",
        _WALL,
        "wall time of perception (rendering the cameras and fusing the cloud; the first attempt "
        "also makes the sensor)",
    ),
    Column("planning_s", "float", _WALL, "wall time of the planner's `plan` call"),
    Column(
        "execution_s",
        "float",
        _WALL,
        "wall time from motion planning to the outcome (includes `motion_planning_s`)",
    ),
    Column(
        "motion_planning_s",
        "float",
        _WALL,
        "wall time of the inverse kinematics and motion checks, part of `execution_s`",
    ),
    Column(
        "sim_time_s",
        "float",
        _SIM,
        "simulated time of the executed motion (0 when nothing was executed)",
    ),
    Column(
        "planner_stages_s",
        "text",
        "JSON object, s",
        "the planner's own wall time per stage (hsq: `cleaning`, `recovery`, `synthesis`, "
        "`elimination`, `scoring`, `total`); empty when the planner reports none",
    ),
    Column(
        "ranks_tried",
        "count",
        "integer",
        "distinct grasps motion-planned in this attempt (1: the first one tried was executed, "
        "and `hsqbench replay` reproduces it exactly)",
    ),
    Column(
        "detail",
        "text",
        "text",
        "why the attempt ended so, in words (which contact, which IK step, ...); on an error "
        "row, the error",
    ),
    *_PROVENANCE,
)

ROUNDS: tuple[Column, ...] = (
    TRIAL_KEY,
    PLANNER,
    BASE_SEED,
    TRIAL_INDEX,
    SEED,
    OBJECTS,
    Column("n_objects", "int", "integer", "objects placed in the round"),
    Column("objects_cleared", "text", "names joined by `;`", "objects carried into the bin"),
    Column("n_cleared", "count", "integer", "how many (empty on an error row)"),
    Column("clearance_rate", "float", "[0, 1]", "`n_cleared / n_objects`"),
    Column(
        "objects_lost",
        "text",
        "names joined by `;`",
        "objects taken out without being cleared (off the table, out of the cameras' view, or "
        "left on the hand)",
    ),
    Column("n_lost", "count", "integer", "how many"),
    Column(
        "objects_graspable",
        "text",
        "names joined by `;`",
        "objects on which the oracle found a feasible grasp in the settled scene before the first "
        "attempt (empty: not checked)",
    ),
    Column("n_graspable", "count", "integer", "how many (empty: not checked)"),
    Column("n_attempts", "int", "integer", "attempts of the round (0 on an error row)"),
    Column("n_success", "count", "integer", "successful attempts"),
    Column("status", "text", "text", "`ok` or `error`"),
    Column(
        "detail",
        "text",
        "text",
        "draws rejected before the round's objects (not placeable, or a pile that did not "
        "settle), or the error",
    ),
    *_PROVENANCE,
)

ATTEMPT_COLUMNS: tuple[str, ...] = tuple(c.name for c in ATTEMPTS)
ROUND_COLUMNS: tuple[str, ...] = tuple(c.name for c in ROUNDS)
_BY_NAME = {"attempts": {c.name: c for c in ATTEMPTS}, "rounds": {c.name: c for c in ROUNDS}}


def column(table: str, name: str) -> Column:
    """The column ``name`` of ``table`` (``attempts`` or ``rounds``)."""
    return _BY_NAME[table][name]
