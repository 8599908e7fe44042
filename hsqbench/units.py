"""Is a size in metres? Mesh and cloud files carry no unit: one check, shared by ``assets
import`` (a mesh) and ``plan`` (a cloud), refuses a size no graspable scene has and names the
``--scale`` that makes it metres ("looks like millimetres: pass --scale 0.001")."""

from __future__ import annotations

#: Units a file is commonly written in, tried in this order for the fix: metres per unit.
LIKELY_UNITS = (("millimetres", 0.001), ("centimetres", 0.01))


def check_metres(
    label: str, extent: float, scale: float, *, min_m: float, max_m: float, small: str, large: str
) -> None:
    """Refuse ``label`` when its largest extent (file units) times ``scale`` is outside
    [``min_m``, ``max_m``] metres; ``small`` and ``large`` say why a size beyond each bound is
    not one in metres (e.g. "under the 5 mm the cameras can see").

    Raises:
        ValueError: one line naming ``label``, its size and the ``--scale`` to pass.
    """
    size_m = extent * scale
    if min_m <= size_m <= max_m:
        return
    if size_m > max_m:
        fix = next(
            (
                f"looks like {unit}: pass --scale {factor:g}"
                for unit, factor in LIKELY_UNITS
                if min_m <= extent * factor <= max_m and factor < scale
            ),
            f"pass the --scale that turns its units into metres (size / {max_m:g} m)",
        )
        bound = large
    else:
        fix = (
            "looks like metres: pass --scale 1"
            if min_m <= extent <= max_m and scale != 1.0
            else "pass the --scale that turns its units into metres"
        )
        bound = small
    raise ValueError(f"{label} is {size_m:.4g} m across at --scale {scale:g}, {bound}: {fix}")
