"""VGN/GIGA's simulated clutter removal in the harness (docs/clutter-removal.md)."""
