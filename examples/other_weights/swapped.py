"""vgn and giga with the other weights pairing (swapped.yaml next to this file)."""

from pathlib import Path

from hsqbench.planner.learned.volumetric import VolumetricPlanner

CONFIG = Path(__file__).with_name("swapped.yaml")


class VGNSwapped(VolumetricPlanner):
    name = "vgn-swapped"

    def __init__(self) -> None:
        super().__init__("vgn", CONFIG, name=self.name)


class GIGASwapped(VolumetricPlanner):
    name = "giga-swapped"

    def __init__(self) -> None:
        super().__init__("giga", CONFIG, name=self.name)
