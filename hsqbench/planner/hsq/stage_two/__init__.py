"""Stage two of the paper (Sec. III-B): grasps from the hidden superquadrics.

- :mod:`.plan`: the stage as one call, :func:`~.plan.plan_from_hidden`.
- Synthesis (Sec. III-B2): :mod:`.synthesis` (closing lines on the principal axes and the extra
  families of the eps1 -> 0, eps2 -> 0 and circular cases, rolls every 10 degrees),
  :mod:`.candidates` (the candidate set ``G`` and why each was removed), :mod:`.shape_rows`
  (per-superquadric rows the vectorised steps share), :mod:`.table_lines` (lines the table
  blocks, levelled and lifted; our addition).
- Elimination (Sec. III-B2, the support cylinders and the collision cylinder):
  :mod:`.elimination` (the rules in order), :mod:`.support` (points within the small cylinders
  at the contacts, threshold kappa), :mod:`.roll_collisions` (gripper boxes against obstacle
  points per roll), :mod:`.line_frame` (coordinates along a closing line),
  :mod:`.hidden_bodies` (rule 6: the hand kept out of hidden superquadrics no camera saw
  through; our addition).
- Evaluation (Sec. III-B3, Eq. 5-11): :mod:`.scoring` (``h = h_alpha h_beta h_gamma h_delta``).
"""
