"""``hsqbench plan``: reads every cloud format, prints and writes grasps, refuses bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from hsqbench.cli import main
from hsqbench.cloud_io import write_cloud
from hsqbench.planner.api import PlanningContext, PlanResult
from hsqbench.planner.grasp import Grasp
from hsqbench.planner.registry import register_planner
from tests.shapes import Box, union_cloud, visible_mask


class CentroidPlanner:
    """A stand-in planner: one top-down grasp at the centroid, remembering what it was given."""

    name = "test-centroid"
    seen: list[tuple[np.ndarray, PlanningContext]] = []  # noqa: RUF012

    def plan(self, points, context) -> PlanResult:
        CentroidPlanner.seen.append((np.asarray(points), context))
        if len(points) < 10:
            return PlanResult(grasps=[], reason="fewer than 10 points", planner=self.name)
        rotation = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])
        grasp = Grasp(np.mean(points, axis=0), rotation, 0.03, 0.5, {"h_alpha": 0.5})
        return PlanResult(grasps=[grasp], planner=self.name)


register_planner("test-centroid", lambda config=None: CentroidPlanner(), replace=True)


def box_cloud(seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    box = Box((0.03, 0.02, 0.05), center=np.array([0.0, 0.0, 0.05]))
    cloud = union_cloud((box,), 0.003, rng)
    mask = np.zeros(len(cloud.points), dtype=bool)
    for camera in ([-0.45, -0.45, 0.55], [0.45, 0.45, 0.55]):
        mask |= visible_mask(cloud.points, cloud.normals, np.array(camera))
    return cloud.points[mask] + rng.normal(scale=0.001, size=(mask.sum(), 3))


@pytest.mark.parametrize(
    ("suffix", "binary"),
    [
        (".ply", True),
        (".ply", False),
        (".pcd", True),
        (".pcd", False),
        (".npy", True),
        (".xyz", False),
    ],
)
def test_reads_each_format(tmp_path, capsys, suffix, binary) -> None:
    points = box_cloud()
    path = write_cloud(tmp_path / f"cloud{suffix}", points, binary=binary)
    CentroidPlanner.seen.clear()
    code = main(
        [
            "plan",
            str(path),
            "--planner",
            "test-centroid",
            "--support-plane",
            "0",
            "0",
            "2",
            "0",
            "--seed",
            "3",
            "--scene",
            "packed",
        ]
    )
    assert code == 0
    given, context = CentroidPlanner.seen[-1]
    np.testing.assert_allclose(given, points, atol=1e-9)  # .xyz keeps 9 digits: nanometres
    assert context.support_plane == pytest.approx((0, 0, 1, 0)) and context.seed == 3
    assert context.packed
    out = capsys.readouterr().out
    assert f"{len(points)} points" in out and "1 grasps" in out


def test_hsq_plan_prints_a_table_and_writes_json(tmp_path, capsys) -> None:
    path = write_cloud(tmp_path / "box.npy", box_cloud(1))
    out_json = tmp_path / "out" / "plan.json"
    code = main(
        [
            "plan",
            str(path),
            "--top",
            "3",
            "--json",
            str(out_json),
            "--support-plane",
            "0",
            "0",
            "1",
            "0",
        ]
    )
    assert code == 0
    out = capsys.readouterr().out
    assert "rank" in out and "score" in out and "candidates: synthesised" in out
    data = json.loads(out_json.read_text())
    assert 1 <= len(data["grasps"]) <= 3 and data["n_grasps"] >= len(data["grasps"])
    scores = [g["score"] for g in data["grasps"]]
    assert scores == sorted(scores, reverse=True)
    top = Grasp.from_dict(data["grasps"][0])
    assert top.width < 0.08 and data["input"]["support_plane"] == [0.0, 0.0, 1.0, 0.0]
    assert data["remaining"]["synthesised"] > 0 and "recovery" in data["timings"]


def test_cameras_reach_the_planner_and_the_json(tmp_path, capsys) -> None:
    path = write_cloud(tmp_path / "box.npy", box_cloud(2))
    out_json = tmp_path / "plan.json"
    CentroidPlanner.seen.clear()
    cameras = ["--camera", "-0.45", "-0.45", "0.55", "--camera", "0.45", "0.45", "0.55"]
    argv = ["plan", str(path), "--planner", "test-centroid", "--json", str(out_json), *cameras]
    assert main(argv) == 0
    _, context = CentroidPlanner.seen[-1]
    np.testing.assert_allclose(context.camera_positions, [[-0.45, -0.45, 0.55], [0.45, 0.45, 0.55]])
    assert json.loads(out_json.read_text())["input"]["camera_positions"] == [
        [-0.45, -0.45, 0.55],
        [0.45, 0.45, 0.55],
    ]
    assert main(["plan", str(path), "--planner", "test-centroid"]) == 0
    assert CentroidPlanner.seen[-1][1].camera_positions is None
    with pytest.raises(SystemExit) as exc:
        main(["plan", str(path), "--camera", "1", "2"])
    assert exc.value.code == 2 and "--camera" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("content", "name", "needle"),
    [
        (b"", "empty.ply", "not a PLY"),
        (b"1 2 3\nnan 1 1\n", "bad.xyz", "NaN or inf"),
        (b"# nothing here\n", "blank.xyz", "no points"),
        (b"v 1 2 3\n", "mesh.obj", "unknown cloud format"),
    ],
)
def test_bad_files_exit_nonzero_with_a_message(tmp_path, capsys, content, name, needle) -> None:
    path = tmp_path / name
    path.write_bytes(content)
    assert main(["plan", str(path)]) == 2
    err = capsys.readouterr().err
    assert "hsqbench plan: error:" in err and needle in err


def test_missing_file_unknown_planner_and_no_grasp(tmp_path, capsys) -> None:
    assert main(["plan", str(tmp_path / "missing.npy")]) == 2
    assert "no such file" in capsys.readouterr().err
    path = write_cloud(tmp_path / "few.npy", np.zeros((4, 3)) + np.arange(4)[:, None])
    assert main(["plan", str(path), "--planner", "nope"]) == 2
    assert "choose one of" in capsys.readouterr().err
    assert main(["plan", str(path), "--planner", "test-centroid"]) == 1
    assert "no grasp: fewer than 10 points" in capsys.readouterr().out


def test_the_example_planner_plans_from_its_file(tmp_path, capsys) -> None:
    path = write_cloud(tmp_path / "box.npy", box_cloud(1))
    spec = str(Path(__file__).resolve().parents[1] / "examples/topdown.py") + ":TopDown"
    assert main(["plan", str(path), "--planner", spec, "--support-plane", "0", "0", "1", "0"]) == 0
    out = capsys.readouterr().out
    assert "1 grasps; best 1:" in out and "time: cleaning" in out


@pytest.mark.parametrize(
    ("factor", "scale", "fix"),
    [
        (1000.0, 1.0, "looks like millimetres: pass --scale 0.001"),
        (1e9, 1.0, "pass the --scale that turns its units into metres"),
        (1.0, 0.001, "looks like metres: pass --scale 1"),
    ],
)
def test_a_cloud_in_other_units_names_the_scale(tmp_path, capsys, factor, scale, fix) -> None:
    """A cloud in millimetres (or x1e9) was planned on and called too sparse; now it is refused
    before planning with the check `assets import` makes of a mesh."""
    path = write_cloud(tmp_path / "box.npy", box_cloud() * factor)
    CentroidPlanner.seen.clear()
    argv = ["plan", str(path), "--planner", "test-centroid", "--scale", str(scale)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and fix in err and f"{path} is " in err
    assert CentroidPlanner.seen == []  # refused before the planner ran


def test_scale_turns_a_cloud_in_millimetres_into_metres(tmp_path, capsys) -> None:
    points = box_cloud()
    path = write_cloud(tmp_path / "box_mm.npy", points * 1000.0)
    CentroidPlanner.seen.clear()
    assert main(["plan", str(path), "--planner", "test-centroid", "--scale", "0.001"]) == 0
    np.testing.assert_allclose(CentroidPlanner.seen[-1][0], points, atol=1e-12)


def test_a_cloud_at_one_place_is_named_so(tmp_path, capsys) -> None:
    path = write_cloud(tmp_path / "one.xyz", np.array([[0.1, 0.2, 0.3]] * 4), binary=False)
    assert main(["plan", str(path)]) == 2
    assert capsys.readouterr().err.strip().endswith("all its 4 point(s) are at one place")
