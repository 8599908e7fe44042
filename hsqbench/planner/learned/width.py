"""Where ``P_G`` lies on a network grasp's closing line, and its width (pure numpy).

Each network grasp comes with a contact point ``c`` (a cloud point), a closing axis ``x`` and a
pose whose origin the forward pass places ``clamp(w, -0.08, 0.04) / 2`` along ``x`` from ``c``.
The width head ``w`` of the cgn-pytorch 0.4.3 weights is unscaled (:mod:`.network`), so the
pose ends up 4 cm (or -2 cm) from ``c`` whatever the object. Two ways to place the grasp:

- ``network``: as the package does, ``P_G`` = the pose's fingertip centre; width = twice its
  distance from ``c`` (so one finger is at ``c``).
- ``cloud`` (our addition): the object's extent along the closing line from the cloud. Cloud
  points within ``radius_m`` of the line through ``c`` are collected on both sides of ``c``
  (farther than ``min_width_m``, nearer than ``max_reach_m``); the side with the farther point is
  the object's, that farthest point is the other contact, and ``P_G`` is midway. A line whose far
  side was never seen (no point beyond ``min_width_m`` on either side) keeps the ``network``
  placement.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
#: Grasp-by-point pairs processed at once (memory bound).
_CHUNK_PAIRS = 2_000_000


def farthest_along(
    cloud: Array, origins: Array, directions: Array, radius_m: float, t_min: float, t_max: float
) -> tuple[Array, Array]:
    """For each line (origin, unit direction): the largest ``+t`` and the largest ``-t`` (as a
    positive number) of cloud points within ``radius_m`` of it with ``t_min < |t| <= t_max``;
    0 where there is none. Returns ``(forward (G,), backward (G,))``."""
    g = origins.shape[0]
    forward, backward = np.zeros(g), np.zeros(g)
    block = max(1, _CHUNK_PAIRS // max(cloud.shape[0], 1))
    for start in range(0, g, block):
        o, d = origins[start : start + block], directions[start : start + block]
        rel = cloud[None, :, :] - o[:, None, :]
        t = np.einsum("gmi,gi->gm", rel, d)
        dist2 = np.einsum("gmi,gmi->gm", rel, rel) - t * t
        near = (dist2 <= radius_m * radius_m) & (np.abs(t) > t_min) & (np.abs(t) <= t_max)
        forward[start : start + block] = np.max(np.where(near & (t > 0), t, 0.0), axis=1)
        backward[start : start + block] = np.max(np.where(near & (t < 0), -t, 0.0), axis=1)
    return forward, backward


def place_on_cloud(
    cloud: Array,
    contacts: Array,
    closing: Array,
    network_centres: Array,
    radius_m: float,
    min_width_m: float,
    max_reach_m: float,
) -> tuple[Array, Array, NDArray[np.bool_]]:
    """``P_G`` (G, 3), widths (G,) and whether the cloud decided (G,) (module notes, ``cloud``)."""
    forward, backward = farthest_along(cloud, contacts, closing, radius_m, min_width_m, max_reach_m)
    far = np.maximum(forward, backward)
    side = np.where(forward >= backward, 1.0, -1.0)
    found = far > 0.0
    centres = contacts + (0.5 * far * side)[:, None] * closing
    net_width = 2.0 * np.linalg.norm(network_centres - contacts, axis=1)
    return (
        np.where(found[:, None], centres, network_centres),
        np.where(found, far, net_width),
        found,
    )
