"""Subcommands of the ``hsqbench`` CLI, one module each (see ``hsqbench.cli``)."""
