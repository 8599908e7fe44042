"""Stage one of the paper (Sec. III-A): hidden superquadrics recovered from a point cloud.

- :mod:`.recovery`: the stage as one call, :func:`~.recovery.recover_hidden_superquadrics`:
  K + 1 seeds, one fit each, fit measures, duplicates merged.
- :mod:`.seeds`: the K-means parts and the ellipsoids whose moment of inertia is half the part's
  (the seeds of Sec. III-A, K of the paper).
- :mod:`.ems`: the outlier/superquadric mixture model (Eq. 3 and 4) and its inference.
- :mod:`.radial`: the radial distance to the surface and its Jacobian, the residual of the fits.
- :mod:`.clusters`: a packed scene split into objects, each recovered on its own (our addition).
"""
