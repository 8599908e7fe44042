"""The episode viewer: trials recorded to Rerun ``.rrd`` files.

- :mod:`hsqbench.viz.rerun_recorder`: :class:`RerunRecorder`, the trial runner's recorder; what
  it logs of the scene, the cameras and the plan: :mod:`hsqbench.viz.rerun_scene`,
  :mod:`hsqbench.viz.rerun_cameras`, :mod:`hsqbench.viz.rerun_plan`.
- :mod:`hsqbench.viz.rrd`: reading a recording back (entities, timelines, texts).
- :mod:`hsqbench.viz.scene_geometry`, :mod:`hsqbench.viz.gripper_outline`,
  :mod:`hsqbench.viz.colors`: what is drawn and how.

Nothing here is imported unless a recording is asked for (``--rerun``), so ``rerun`` costs
nothing when recording is off.
"""
