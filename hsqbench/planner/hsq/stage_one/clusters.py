"""Objects of a packed scene: the cloud split into Euclidean clusters.

Packed scenes place objects apart (``scene.yaml`` ``placement.margin_m``), so the points of one
object are linked by chains of neighbours closer than ``cluster_distance_m`` and two objects'
are not. Stage one then runs on each object's points as it would on an isolated object: one
whole-object fit and K parts by the paper's rule each, instead of one fit around the scene and
K parts shared by five objects (``hsq``, :mod:`hsqbench.planner.hsq.planner`); ``single-sq`` fits one
superquadric per cluster. Touching objects stay one cluster, which is the unsplit case.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from hsqbench.planner.downsample import voxel_downsample
from hsqbench.planner.hsq.config import RecoveryConfig


def object_clusters(cloud: NDArray[np.float64], config: RecoveryConfig) -> list[NDArray[np.int64]]:
    """Indices into ``cloud`` (N, 3) of each object: connected components of the voxel
    centroids (``cluster_voxel_m``) linked within ``cluster_distance_m``, largest first, those
    with fewer than ``min_cluster_points`` points left out."""
    down = voxel_downsample(cloud, config.cluster_voxel_m)
    pairs = cKDTree(down.points).query_pairs(config.cluster_distance_m, output_type="ndarray")
    m = down.points.shape[0]
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(m, m))
    _, voxel_label = connected_components(graph, directed=False)
    label = voxel_label[down.inverse]
    sizes = np.bincount(label)
    keep = np.flatnonzero(sizes >= config.min_cluster_points)
    order = keep[np.argsort(-sizes[keep], kind="stable")]
    members = np.argsort(label, kind="stable")
    starts = np.concatenate([[0], np.cumsum(sizes)])
    return [members[starts[c] : starts[c + 1]] for c in order]
