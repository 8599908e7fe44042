"""Source (a): the YCB objects in ``HSQ_YCB_DIR``.

Layout (as written by ``hsqbench assets download`` and as in the shared copy)::

    HSQ_YCB_DIR/
        objects.csv                 # columns name,ycb_id,mass_kg (official YCB masses, kg)
        <name>/textured.obj         # Google 16k scan, metres, z up
        <name>/textured.mtl
        <name>/texture_map.png

The YCB Object and Model Set (Calli et al., IEEE RAM 2015) is licensed CC BY 4.0: results and
images made with these models must credit it.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

from hsqbench.settings import ycb_dir

CSV_NAME = "objects.csv"
CSV_COLUMNS = ("name", "ycb_id", "mass_kg")
MESH_NAME = "textured.obj"
TEXTURE_NAME = "texture_map.png"
MTL_NAME = "textured.mtl"


@dataclass(frozen=True)
class YcbEntry:
    """One YCB object: its folder name, YCB id (e.g. ``"025"``) and official mass in kg."""

    name: str
    ycb_id: str
    mass_kg: float
    folder: Path

    @property
    def mesh_path(self) -> Path:
        return self.folder / MESH_NAME

    @property
    def texture_path(self) -> Path | None:
        path = self.folder / TEXTURE_NAME
        return path if path.is_file() else None


def read_objects_csv(root: Path) -> list[YcbEntry]:
    """Parse ``root/objects.csv`` in file order; errors name the file, row and fix."""
    path = root / CSV_NAME
    if not path.is_file():
        raise FileNotFoundError(
            f"{path} is missing: a YCB folder needs objects.csv with columns {','.join(CSV_COLUMNS)} "
            "(`hsqbench assets download --dest DIR` writes it)"
        )
    with path.open(newline="") as f:
        reader = csv.DictReader(f)
        missing = [c for c in CSV_COLUMNS if c not in (reader.fieldnames or [])]
        if missing:
            raise ValueError(
                f"{path}: missing column(s) {missing}; expected {','.join(CSV_COLUMNS)}"
            )
        entries = []
        for line, row in enumerate(reader, start=2):
            name = (row["name"] or "").strip()
            try:
                mass = float(row["mass_kg"])
            except (TypeError, ValueError):
                mass = math.nan
            if not name or not math.isfinite(mass) or mass <= 0.0:
                raise ValueError(
                    f"{path}, line {line}: need a name and a positive mass_kg, got {dict(row)}"
                )
            entries.append(YcbEntry(name, (row["ycb_id"] or "").strip(), mass, root / name))
    names = [e.name for e in entries]
    if len(set(names)) != len(names):
        raise ValueError(
            f"{path}: duplicate object names {sorted({n for n in names if names.count(n) > 1})}"
        )
    return entries


def ycb_entries(required: bool = True) -> list[YcbEntry]:
    """The objects of ``HSQ_YCB_DIR`` (empty when unset and not ``required``)."""
    root = ycb_dir(required=required)
    return [] if root is None else read_objects_csv(root)


def ycb_entry(name: str) -> YcbEntry | None:
    """The entry of ``name`` if ``HSQ_YCB_DIR`` is set and lists it."""
    return next((e for e in ycb_entries(required=False) if e.name == name), None)
