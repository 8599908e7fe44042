"""The error a bad config raises, below both the loader (:mod:`hsqbench.config`) and the override
paths it applies (:mod:`hsqbench.overrides`), so that neither imports the other for it."""

from __future__ import annotations


class ConfigError(ValueError):
    """A configuration file or mapping does not match its dataclass."""
