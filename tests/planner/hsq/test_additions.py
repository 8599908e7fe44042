"""Additions of ours behind switches: every switch changes what the planner does on a case built
for it, ``hsq-paper`` turns them all off (the table rule stays), ``hsq-no-<name>`` one."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

from hsqbench.config import from_dict
from hsqbench.errors import ConfigError
from hsqbench.planner.api import PlanningContext
from hsqbench.planner.cleaning import clean_cloud
from hsqbench.planner.hsq.additions import ADDITIONS, AdditionsConfig, ablation_planners, all_off
from hsqbench.planner.hsq.config import PlannerConfig, load_planner_config
from hsqbench.planner.hsq.planner import HSQPlanner
from hsqbench.planner.hsq.stage_one.recovery import (
    fit_superquadric,
    recover_hidden_superquadrics,
    surface_spacing,
)
from hsqbench.planner.hsq.stage_two.candidates import CandidateSet, ClosingLines
from hsqbench.planner.hsq.stage_two.elimination import eliminate, support_kappa
from hsqbench.planner.hsq.stage_two.plan import plan_from_hidden
from hsqbench.planner.hsq.stage_two.synthesis import synthesize
from hsqbench.planner.hsq.stage_two.table_lines import LEVELLED, PINCHED, level_table_lines
from hsqbench.planner.registry import get_planner, planner_names
from hsqbench.superquadric.geometry import Superquadric
from tests.planner.baselines.test_baselines import two_boxes_apart
from tests.planner.hsq.stage_two.test_elimination import (
    GRIPPER,
    ROLLS,
    one_line,
    patch,
    reasons,
    two_faces,
)
from tests.planner.hsq.stage_two.test_table_lines import lying_bar
from tests.planner.hsq.test_planner import CAMERAS, seen
from tests.shapes import (
    Box,
    mug_with_handle,
    random_superquadric,
    superquadric_cloud,
    union_cloud,
)

TABLE = np.array([0.0, 0.0, 1.0, 0.0])
BEHIND = np.array([[0.6, 0.3, 0.3], [0.6, -0.3, 0.3]])  # cameras on the +x side


def with_all() -> PlannerConfig:
    """Every addition on (the default has some off: configs/planner.yaml says why)."""
    return PlannerConfig(additions=AdditionsConfig(**dict.fromkeys(AdditionsConfig.names(), True)))


def without(name: str) -> PlannerConfig:
    """Every addition on but ``name``."""
    on = dict.fromkeys(AdditionsConfig.names(), True)
    return PlannerConfig(additions=AdditionsConfig(**{**on, name: False}))


def mug_cloud() -> np.ndarray:
    rng = np.random.default_rng(6)
    pc = union_cloud(mug_with_handle(), 0.002, rng)
    return pc.points + rng.normal(scale=0.001, size=pc.points.shape)


def fingerprint(hidden) -> list:
    return [np.round(h.superquadric.to_vector(), 4).tolist() for h in hidden]


def line_reasons(cfg: PlannerConfig, half: float, cloud: np.ndarray, **kwargs) -> set[str]:
    cands = one_line(half)
    eliminate(cands, cloud, GRIPPER, cfg.grasp, **kwargs)
    return set(reasons(cands))


# Each case returns (with the addition, without it); the two must differ as stated.
def case_thinning(cfg: PlannerConfig):
    rng = np.random.default_rng(0)
    dense = union_cloud((Box((0.03, 0.02, 0.04), center=np.zeros(3)),), 0.0005, rng).points
    return len(clean_cloud(dense, cfg.cleaning).points) / len(dense)


def case_outlier_removal(cfg: PlannerConfig):
    cloud = np.concatenate([two_faces(0.02), [[0.5, 0.5, 0.5]]])
    return clean_cloud(cloud, cfg.cleaning).n_removed


def case_object_split(cfg: PlannerConfig):
    # Two boxes placed apart in a packed scene: whole-object fits (seed 0).
    _, _, points = two_boxes_apart()
    context = PlanningContext(support_plane=TABLE, packed=True, seed=0)
    hidden = HSQPlanner(cfg).plan(points, context).hidden_superquadrics
    return sum(h.seed == 0 for h in hidden)


def case_extra_parts(cfg: PlannerConfig):
    return fingerprint(recover_hidden_superquadrics(mug_cloud(), cfg.recovery, seed=0))


def case_fit_dedup(cfg: PlannerConfig):
    return len(recover_hidden_superquadrics(mug_cloud(), cfg.recovery, seed=0))


def case_multi_start(cfg: PlannerConfig):
    # A one-sided view of a random superquadric (seed found among 40) on which the ellipsoid
    # start alone ends in a worse optimum: the cost (nats per point) of the fit.
    rng = np.random.default_rng(26)
    cloud = superquadric_cloud(random_superquadric(rng), rng, one_sided=True).points
    return fit_superquadric(cloud, config=cfg.recovery).cost


def case_sigma_annealing(cfg: PlannerConfig):
    return fingerprint(recover_hidden_superquadrics(mug_cloud(), cfg.recovery, seed=0))


def case_caps(cfg: PlannerConfig):
    scene = Superquadric(0.1, 0.1, [0.25, 0.2, 0.06])  # a packed scene's whole-scene fit
    return surface_spacing(scene, cfg.recovery)


def case_thin_parts(cfg: PlannerConfig):
    return len(synthesize([Superquadric(1.0, 1.0, [0.002, 0.015, 0.02])], cfg.grasp).lines)


def case_slide_all_shapes(cfg: PlannerConfig):
    bottle = Superquadric(0.8, 0.8, [0.03, 0.05, 0.1])
    return int(np.count_nonzero(synthesize([bottle], cfg.grasp).lines.family == "slide"))


def case_antipodal_check(cfg: PlannerConfig):
    rounded = Superquadric(0.45, 0.1, [0.03, 0.02, 0.05])
    return float(np.abs(synthesize([rounded], cfg.grasp).lines.centres[:, 2]).max())


def case_table_lines(cfg: PlannerConfig):
    bar = lying_bar(0.015, 0.018, tilt_deg=8.0)
    surface, _ = bar.sample_surface(0.002)
    hidden = [SimpleNamespace(superquadric=bar, alpha=0.001, beta=0.9)]
    res = plan_from_hidden(surface, hidden, cfg.grasp, gripper=GRIPPER, support_plane=TABLE)
    return int(np.count_nonzero(res.candidates.lines.family == LEVELLED))


def case_pinch(cfg: PlannerConfig):
    bar = lying_bar(0.005, 0.005, eps2=0.1)  # a 10 mm square bar lying on the table
    cands = synthesize([bar], cfg.grasp)
    level_table_lines(cands, [bar], TABLE, GRIPPER, cfg.grasp)
    return int(np.count_nonzero(cands.lines.family == PINCHED))


def case_duplicate_lines(cfg: PlannerConfig):
    base = one_line(0.02).lines
    near = one_line(0.021, centre=(0.001, -0.001, 0.0), direction=(-1.0, 0.02, 0.0)).lines
    cands = CandidateSet(ClosingLines.concatenate([base, near]), ROLLS)
    eliminate(cands, two_faces(0.02), GRIPPER, cfg.grasp, line_priority=np.array([0.5, 0.9]))
    return int(np.count_nonzero(cands.rejected_by == "duplicate"))


def case_opening_margin(cfg: PlannerConfig):
    return line_reasons(cfg, 0.039, two_faces(0.039))  # 78 mm contacts, 80 mm opening


def case_support_fraction(cfg: PlannerConfig):
    return support_kappa(0.001, cfg.grasp)


def case_support_facing(cfg: PlannerConfig):
    # The +x contact sees a surface tilted 60 deg from the line (an edge), the -x one a face.
    slanted = patch((0.02, 0, 0), (np.cos(np.pi / 3), 0.0, np.sin(np.pi / 3)), radius=0.009)
    cloud = np.concatenate([slanted, patch((-0.02, 0, 0), (-1, 0, 0))])
    return line_reasons(cfg, 0.02, cloud)


def case_unseen_waiver(cfg: PlannerConfig):
    one_face = patch((0.02, 0, 0), (1, 0, 0))  # the -x face is unseen from BEHIND
    return line_reasons(cfg, 0.02, one_face, camera_positions=BEHIND)


def case_sweep(cfg: PlannerConfig):
    wall = patch((0.05, 0.0, 0.0), (1, 0, 0), radius=0.02)  # where the open finger goes
    return line_reasons(cfg, 0.02, np.concatenate([two_faces(0.02), wall]))


def case_hidden_bodies(cfg: PlannerConfig):
    # A hidden body where the open +x finger goes, which the cloud does not show.
    body = patch((0.05, 0.0, 0.0), (1, 0, 0), radius=0.02)
    return line_reasons(cfg, 0.02, two_faces(0.02), body_points=body)


#: name -> (case, check(with, without)).


def case_redraw(cfg: PlannerConfig):
    # A 10 cm cube, wider than the opening every way: no grasp on any draw, so the reason
    # says how many draws were made.
    points = seen([Box((0.05, 0.05, 0.05), center=np.array([0.0, 0.0, 0.05]))])
    context = PlanningContext(support_plane=TABLE, seed=0, camera_positions=CAMERAS)
    return HSQPlanner(cfg).plan(points, context).reason


CASES = {
    "thinning": (case_thinning, lambda on, off: on < 0.25 and off == 1.0),
    "outlier_removal": (case_outlier_removal, lambda on, off: on == 1 and off == 0),
    "object_split": (case_object_split, lambda on, off: on == 2 and off == 1),
    "extra_parts": (case_extra_parts, lambda on, off: on != off),
    "fit_dedup": (case_fit_dedup, lambda on, off: on < off),
    "multi_start": (case_multi_start, lambda on, off: on < off - 0.1),
    "sigma_annealing": (case_sigma_annealing, lambda on, off: on != off),
    "caps": (case_caps, lambda on, off: on > 0.003 and off == pytest.approx(0.003)),
    "thin_parts": (case_thin_parts, lambda on, off: on == 0 < off),
    "slide_all_shapes": (case_slide_all_shapes, lambda on, off: on > 0 == off),
    "antipodal_check": (case_antipodal_check, lambda on, off: on < off),
    "table_lines": (case_table_lines, lambda on, off: on > 0 == off),
    "pinch": (case_pinch, lambda on, off: on > 0 == off),
    "duplicate_lines": (case_duplicate_lines, lambda on, off: on > 0 == off),
    "opening_margin": (case_opening_margin, lambda on, off: on == {"width"} and "width" not in off),
    "support_fraction": (case_support_fraction, lambda on, off: on > off == 5),
    "support_facing": (case_support_facing, lambda on, off: on == {"support"} and off == {""}),
    "unseen_waiver": (case_unseen_waiver, lambda on, off: on == {""} and off == {"support"}),
    "sweep": (case_sweep, lambda on, off: on == {"sweep"} and off == {""}),
    "hidden_bodies": (case_hidden_bodies, lambda on, off: on == {"hidden"} and off == {""}),
    "redraw": (case_redraw, lambda on, off: "on each of 3 draws" in on and "draws" not in off),
}


def test_every_addition_has_a_case_and_its_paper_values_name_real_fields() -> None:
    assert set(CASES) == set(ADDITIONS) == set(AdditionsConfig.names())
    defaults = PlannerConfig()
    for name, addition in ADDITIONS.items():
        section = getattr(defaults, addition.section)
        assert set(addition.paper) <= {f.name for f in dataclasses.fields(section)}, name
        assert addition.superseded_by in (None, *set(ADDITIONS) - {name}), name


@pytest.mark.parametrize("name", sorted(CASES))
def test_each_switch_changes_the_planner(name: str) -> None:
    case, check = CASES[name]
    on, off = case(with_all()), case(without(name))
    assert check(on, off), (on, off)


def test_a_switch_off_sets_the_paper_values_and_only_those() -> None:
    ours = load_planner_config()
    for name, addition in ADDITIONS.items():
        paper = ours.with_additions(AdditionsConfig(**{name: False}))
        for section in ("cleaning", "recovery", "grasp"):
            a, b = getattr(ours, section), getattr(paper, section)
            changed = {
                f.name for f in dataclasses.fields(a) if getattr(a, f.name) != getattr(b, f.name)
            }
            expected = set(addition.paper) if section == addition.section else set()
            assert changed <= expected, (name, section, changed)
        section = getattr(paper, addition.section)
        assert all(getattr(section, k) == v for k, v in addition.paper.items())


def test_hsq_paper_and_the_ablation_planners_are_registered() -> None:
    names = planner_names()
    assert "hsq-paper" in names
    assert set(ablation_planners()) <= set(names)
    assert len(ablation_planners()) == len(ADDITIONS)
    paper = get_planner("hsq-paper")
    assert paper.name == "hsq-paper" and set(paper.config.additions.off()) == set(ADDITIONS)
    one = get_planner("hsq-no-unseen-waiver")
    assert one.name == "hsq-no-unseen-waiver"
    assert set(one.config.additions.off()) == {
        "unseen_waiver",
        *load_planner_config().additions.off(),
    }
    assert get_planner("hsq").config.additions.off() == load_planner_config().additions.off()


def test_hsq_paper_keeps_the_table_rule_and_labels_its_results() -> None:
    rng = np.random.default_rng(1)
    box = Box((0.03, 0.02, 0.05), center=np.array([0.5, 0.0, 0.05]))
    cloud = union_cloud((box,), 0.002, rng).points
    cloud = cloud[cloud[:, 2] > 0.003]
    result = get_planner("hsq-paper").plan(cloud, PlanningContext(support_plane=tuple(TABLE)))
    assert result.planner == "hsq-paper"
    assert result.removed_by["table"] > 0 and result.removed_by["sweep"] == 0
    assert result.grasps, result.reason


def test_switches_are_checked() -> None:
    with pytest.raises(ConfigError, match="additions"):
        from_dict(PlannerConfig, {"additions": {"no_such_thing": False}})
    with pytest.raises(ValueError, match="unknown addition"):
        get_planner("hsq").__class__(additions_off=("no_such_thing",))
    assert all_off().off() == AdditionsConfig.names()
