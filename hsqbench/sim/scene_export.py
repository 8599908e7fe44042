"""Write a composed scene as a self-contained MJCF folder (``hsqbench scene --mjcf DIR``).

``DIR/scene.xml`` holds the whole scene (static world, Panda, objects) with the settled state as
its keyframe ``initial``; ``DIR/assets/`` holds a copy of every mesh and texture file it uses, so
the folder can be moved, opened with ``python -m mujoco.viewer --mjcf DIR/scene.xml`` or used
in another project. Object meshes are the built assets of the library; the robot's are
Menagerie's (Apache-2.0) and the YCB ones are CC BY 4.0: ``DIR/ATTRIBUTION.md`` says so.

MuJoCo's XML writer keeps 6 significant digits, so the exported model differs from the
in-memory one in the 6th digit of its numbers (masses, poses, the keyframe); over 0.5 s of
simulation a packed scene's state differed by 5e-7 (``tests/test_scene_export.py``).
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import mujoco

from hsqbench.sim.robot import RobotConfig, load_robot_config, menagerie_path
from hsqbench.sim.scene import INITIAL_KEY, SceneInfo

SCENE_FILE = "scene.xml"
ASSETS = "assets"
ATTRIBUTION = """# Scene {name}

Exported by hsqbench (`hsqbench scene --scene {kind} --seed {seed} --mjcf DIR`): open it with
`python -m mujoco.viewer --mjcf {scene}` (the keyframe `initial` is the settled scene).

- Robot: MuJoCo Menagerie `franka_emika_panda` (Apache-2.0), with hsqbench's documented changes.
- Objects: {objects}. YCB objects are from the YCB Object and Model Set (Calli et al., IEEE
  RAM 2015), CC BY 4.0: results and images made with them must credit it.
"""


def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name)


def _source(file: str, search: list[Path]) -> Path:
    path = Path(file)
    if path.is_absolute():
        return path
    for folder in search:
        if (folder / path).is_file():
            return folder / path
    raise FileNotFoundError(f"cannot find the file {file!r} of the scene (looked in {search})")


def export_scene(
    spec: mujoco.MjSpec,
    model: mujoco.MjModel,
    info: SceneInfo,
    out_dir: Path,
    robot: RobotConfig | None = None,
) -> Path:
    """Write ``spec`` (as built by :func:`hsqbench.sim.scene.build_scene_spec`, with ``model``
    its compiled model holding the settled keyframe) into ``out_dir``; returns the scene file.

    The folder is written aside and renamed into place, so a failure leaves nothing half-made.
    """
    robot = robot or load_robot_config()
    panda_xml = menagerie_path(robot)
    panda_assets = panda_xml.parent / (mujoco.MjSpec.from_file(str(panda_xml)).compiler.meshdir)
    search = [panda_assets, panda_xml.parent]
    out_dir = Path(out_dir)
    tmp = out_dir.with_name(f".{out_dir.name}.tmp")
    if tmp.exists():
        shutil.rmtree(tmp)
    (tmp / ASSETS).mkdir(parents=True)
    try:
        copied: dict[Path, str] = {}
        for item in [*spec.meshes, *spec.textures]:
            if not item.file:
                continue  # a built-in texture (sky, floor)
            source = _source(item.file, search)
            if source not in copied:
                copied[source] = f"{len(copied):04d}_{_safe(source.name)}"
                shutil.copyfile(source, tmp / ASSETS / copied[source])
            # Absolute while MuJoCo writes the XML (it compiles the spec), relative in the file.
            item.file = str((tmp / ASSETS / copied[source]).resolve())
        key = spec.key(INITIAL_KEY)
        k = model.key(INITIAL_KEY).id
        key.qpos = model.key_qpos[k].tolist()
        key.qvel = model.key_qvel[k].tolist()
        key.ctrl = model.key_ctrl[k].tolist()
        key.time = float(model.key_time[k])
        xml = spec.to_xml().replace(f"{(tmp / ASSETS).resolve()}/", f"{ASSETS}/")
        (tmp / SCENE_FILE).write_text(xml)
        (tmp / "ATTRIBUTION.md").write_text(
            ATTRIBUTION.format(
                name=spec.modelname,
                kind=info.kind,
                seed=info.seed,
                scene=out_dir / SCENE_FILE,
                objects=", ".join(info.objects) or "none",
            )
        )
        mujoco.MjModel.from_xml_path(str(tmp / SCENE_FILE))  # it must open on its own
        if out_dir.exists():
            shutil.rmtree(out_dir)
        tmp.rename(out_dir)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return out_dir / SCENE_FILE
