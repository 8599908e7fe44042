"""Superquadric geometry shared by both stages of the planner (paper Sec. II-A, Eq. 1).

Modules, each importing only those above it:

- :mod:`.primitives`: the overflow-free nested lp norms (``phi``), shape-exponent bounds,
  arc-length quarter curves, input checks.
- :mod:`.curvature`: analytic Gaussian curvature (the ``gamma`` of Sec. III-B3, Eq. 10).
- :mod:`.sampling`: even surface sampling with outward normals (the set ``S`` of Eq. 6 and 8).
- :mod:`.mesh`: a watertight triangle mesh (spherical product of Eq. 1).
- :mod:`.geometry`: :class:`~hsqbench.superquadric.geometry.Superquadric`, the 11 parameters
  (Eq. 1 and a pose), its inside-outside function, radial distance, normals and volume.
- :mod:`.fit`: the paper's fit measures ``alpha`` (Eq. 6) and ``beta`` (Eq. 8).
"""
