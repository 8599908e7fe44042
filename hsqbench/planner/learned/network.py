"""The Contact-GraspNet network of ``cgn-pytorch`` (0.4.3): loading and one seeded forward pass.

The package's own ``inference()`` is not used: it subsamples with Python's global ``random`` and
prints. Here the same forward pass runs (with the same ``gripper_width=0.08`` and depth) on a
subsample drawn, and put in an order drawn, from ``numpy.random.default_rng(seed)``. The network's
farthest point sampling is run with ``random_start=False`` here and inside the network (the
package's ``pointnet2.fps`` is replaced once, at load): it then starts at the first point of the
seeded order, and one seed gives one result. torch, torch-geometric and cgn-pytorch are imported
here only.

torch-geometric's ``fps``, ``radius`` and ``knn`` run on :mod:`.cluster_ops` (pure torch), not on
the torch-cluster package (no binary wheel; 11 to 30 minutes to compile). fps and knn give
torch-cluster's indices; ``radius`` keeps, of the points in a ball, the first
``max_num_neighbors`` (64 here) in the input's order, as torch-cluster's CUDA kernel and
PointNet++'s ball query do, where torch-cluster's CPU code kept the first its k-d tree visited.
The input order is a seeded random permutation, so each ball's 64 points are a uniform draw from
it. The CPU results of runs made before this change (with torch-cluster) therefore differ in the
grasps, not in the frames or the harness (docs/contact-graspnet.md).

The width head of the 0.4.3 weights is not usable: its batch-norm running variance is ~1e9 and
its raw outputs on a harness box cloud range from -2600 to +200 (metres), uncorrelated with the
box (r = 0.08). The forward pass clamps them to ``[-0.08, 0.04]`` m before placing the pose, so a
pose sits 4 cm (or -2 cm) from its contact along the closing axis whatever the object; see
:mod:`.width` for how the planner places ``P_G`` instead.
"""

from __future__ import annotations

import contextlib
import functools
import io
import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

#: How to install what this module needs (the error names it when an import fails).
INSTALL_HINT = (
    "the contact-graspnet planner needs the optional 'learned' extra: run "
    "`pip install -e '.[learned]' && pip install --no-deps cgn-pytorch==0.4.3`, or `make learned` "
    "(all from wheels, a minute or two)"
)
#: ``gripper_width`` the package's ``inference()`` hands the forward pass (Franka stroke).
_FORWARD_GRIPPER_WIDTH_M = 0.08


class LearnedExtraMissing(RuntimeError):
    """The optional ``learned`` extra (torch, cgn-pytorch, ...) is not importable."""


@dataclass(frozen=True)
class NetworkOutput:
    """One forward pass, in the frame the cloud was given in.

    Attributes:
        poses: (G, 4, 4) gripper-base poses (see :mod:`hsqbench.planner.learned.frames`).
        confidence: (G,) grasp success probability in [0, 1].
        input_index: (G,) index, into the cloud given, of the contact point of each grasp.
    """

    poses: NDArray[np.float64]
    confidence: NDArray[np.float64]
    input_index: NDArray[np.int64]


def import_backend():
    """``(torch, fps, cgn_pytorch)``, or :class:`LearnedExtraMissing` saying how to install."""
    try:
        with warnings.catch_warnings():  # meshcat's and torch.jit's deprecation notices
            warnings.simplefilter("ignore", DeprecationWarning)
            import cgn_pytorch
            import torch
            from torch_geometric.nn import fps
    except ImportError as exc:
        raise LearnedExtraMissing(f"{INSTALL_HINT} ({exc})") from exc
    from hsqbench.planner.learned import cluster_ops  # imports torch: only once torch is there

    cluster_ops.install()
    return torch, fps, cgn_pytorch


def available() -> bool:
    """Whether the extra imports (for tests and ``planner_names``-style listings)."""
    try:
        import_backend()
    except LearnedExtraMissing:
        return False
    return True


def resolve_device(device: str) -> str:
    """``auto`` -> ``cuda`` when torch sees a GPU, else ``cpu``; ``cuda`` without one is an error."""
    torch, _, _ = import_backend()
    if device == "auto":
        return "cuda" if torch.cuda.is_available() else "cpu"
    if device == "cuda" and not torch.cuda.is_available():
        raise RuntimeError("contact_graspnet.device is 'cuda' but torch sees no CUDA device")
    return device


@functools.lru_cache(maxsize=2)
def load_model(device: str):
    """The pretrained model shipped in the cgn-pytorch wheel, on ``device``, in eval mode."""
    _, fps, cgn_pytorch = import_backend()
    import cgn_pytorch.pointnet2 as pointnet2

    # Deterministic farthest point sampling in the network's deeper layers (module notes).
    pointnet2.fps = functools.partial(fps, random_start=False)
    with contextlib.redirect_stdout(io.StringIO()):  # from_pretrained prints progress
        model, _, _ = cgn_pytorch.from_pretrained(device="cpu" if device == "cpu" else 0)
    model.eval()
    return model


def run_network(
    cloud: NDArray[np.float64], device: str, seed: int, max_points: int, depth_m: float
) -> NetworkOutput:
    """One forward pass on ``cloud`` (N, 3), in the frame the network expects.

    At most ``max_points`` points go in (a seeded subset); the network places its 2048 grasp
    contacts on them by farthest point sampling. ``depth_m``: base-to-contact distance of the
    poses (0.1034 m, the Franka's).

    Raises:
        ValueError: fewer than 64 points (the network's neighbourhoods hold up to 64).
    """
    torch, fps, _ = import_backend()
    if cloud.shape[0] < 64:
        raise ValueError(f"the cloud has {cloud.shape[0]} points; the network needs at least 64")
    rng = np.random.default_rng(seed)
    keep = rng.permutation(cloud.shape[0])[:max_points]
    torch.manual_seed(seed)  # nothing random is left in the forward pass; for safety
    model = load_model(device)
    pcd = torch.as_tensor(cloud[keep], dtype=torch.float32, device=device)
    batch = torch.zeros(pcd.shape[0], dtype=torch.int64, device=device)
    with torch.no_grad(), warnings.catch_warnings():
        # The package calls torch.cross without dim= (a deprecation notice per call).
        warnings.filterwarnings("ignore", message="Using torch.cross without specifying the dim")
        idx = fps(pcd, batch, min(1.0, 2048 / pcd.shape[0]), random_start=False)
        _, poses, logits, _, _, _ = model(
            pcd[:, 3:],
            pcd_poses=pcd,
            batch=batch,
            idxs=idx,
            gripper_depth=depth_m,
            gripper_width=_FORWARD_GRIPPER_WIDTH_M,
        )
    return NetworkOutput(
        poses=poses.reshape(-1, 4, 4).cpu().numpy().astype(np.float64),
        confidence=torch.sigmoid(logits).reshape(-1).cpu().numpy().astype(np.float64),
        input_index=keep[idx.cpu().numpy()],
    )
