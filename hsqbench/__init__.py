"""hsqbench: a MuJoCo benchmark for learning-free grasping with hidden superquadrics."""

__version__ = "0.1.0"
