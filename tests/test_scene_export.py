"""`hsqbench scene --mjcf DIR`: a self-contained MJCF of a composed scene that opens on its own
and steps like the in-memory model."""

from __future__ import annotations

import shutil

import mujoco
import numpy as np
import pytest

from hsqbench.cli import main
from hsqbench.sim.scene import build_scene_spec

OBJECTS = ["proc_box", "proc_cylinder", "proc_l"]


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("HSQ_CACHE_DIR", str(tmp_path / "cache"))


def _step(model: mujoco.MjModel, n: int) -> np.ndarray:
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("initial").id)
    for _ in range(n):
        mujoco.mj_step(model, data)
    return data.qpos.copy()


def test_exported_scene_opens_alone_and_steps_like_the_model(tmp_path, capsys) -> None:
    out = tmp_path / "export"
    args = ["scene", "--scene", "packed", "--seed", "3", "--objects", *OBJECTS, "--mjcf", str(out)]
    assert main(args) == 0
    assert "python -m mujoco.viewer --mjcf" in capsys.readouterr().out
    moved = shutil.move(out, tmp_path / "elsewhere")  # self-contained: no path outside it
    text = (moved / "scene.xml").read_text()
    assert str(tmp_path) not in text and "/cache/" not in text
    exported = mujoco.MjModel.from_xml_path(str(moved / "scene.xml"))

    _, model, _, info = build_scene_spec("packed", OBJECTS, seed=3)
    assert (exported.nbody, exported.ngeom, exported.nq, exported.nu, exported.nmesh) == (
        model.nbody, model.ngeom, model.nq, model.nu, model.nmesh,
    )  # fmt: skip
    np.testing.assert_allclose(exported.geom_size, model.geom_size, atol=1e-9)
    np.testing.assert_allclose(exported.geom_pos, model.geom_pos, atol=1e-9)
    # MuJoCo writes numbers with 6 significant digits (its XML writer's precision).
    np.testing.assert_allclose(exported.body_mass, model.body_mass, rtol=1e-5)
    k = model.key("initial").id
    np.testing.assert_allclose(exported.key_qpos[k], model.key_qpos[k], rtol=1e-5, atol=1e-6)
    for name in info.objects:  # the objects are where the scene settled them
        assert exported.body(f"obj/{name}").id == model.body(f"obj/{name}").id
    steps = round(0.5 / model.opt.timestep)
    drift = np.abs(_step(exported, steps) - _step(model, steps)).max()
    print(f"max qpos difference after {steps} steps: {drift:.2e}")
    assert drift < 1e-5  # metres, radians, quaternion units after 0.5 s (measured 5e-7)
    assert "CC BY 4.0" in (moved / "ATTRIBUTION.md").read_text()
