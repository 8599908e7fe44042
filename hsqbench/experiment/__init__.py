"""The benchmark: protocol, runner, results store and report (analysis apart from running).

- :mod:`~hsqbench.experiment.config`: ``ExperimentConfig`` (``configs/protocols/``).
- :mod:`~hsqbench.experiment.seeds`: the trial list and each trial's derived seed.
- :mod:`~hsqbench.experiment.backend`: ``TrialBackend`` (how one trial runs; ``SimBackend`` calls
  ``hsqbench.sim.trial``) and ``execute_trial`` (exceptions become error records).
- :mod:`~hsqbench.experiment.executor`: in-process, local process pool, or Ray.
- :mod:`~hsqbench.experiment.results`: the append-only CSV store, resume and dedup.
- :mod:`~hsqbench.experiment.runner`: ``run_benchmark``.
- :mod:`~hsqbench.experiment.stats`, :mod:`~hsqbench.experiment.report`,
  :mod:`~hsqbench.experiment.reported`: Wilson intervals, tables and plots, the paper's numbers.
"""
