"""Baseline planners behind the same :class:`~hsqbench.planner.api.Planner` interface."""
