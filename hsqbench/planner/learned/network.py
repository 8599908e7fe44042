"""The Contact-GraspNet network of ``cgn-pytorch`` (0.4.3): loading and one seeded forward pass.

The package's own ``inference()`` is not used: it subsamples with Python's global ``random``,
prints, drops the predicted widths and clamps them to 4 cm (it passes ``gripper_width=0.08`` to
the forward pass, whose clamp is ``[-w, w / 2]``). Here the same forward pass runs with the
Franka's full 8 cm (``gripper_width=0.16``, the forward pass's own default), the subsample is
drawn from ``numpy.random.default_rng(seed)`` and torch's generator (the farthest point
sampling's random start inside the network) is seeded with the same seed, so one seed gives one
result. torch, torch-geometric, torch-cluster and cgn-pytorch are imported here only.
"""

from __future__ import annotations

import contextlib
import functools
import io
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

#: How to install what this module needs (the error names it when an import fails).
INSTALL_HINT = (
    "the contact-graspnet planner needs the optional 'learned' extra: run "
    "`pip install -e '.[learned]'` and then `make learned` (installs cgn-pytorch without its "
    "pinned dependencies and builds torch-cluster from source, about 11 minutes on 2 cores)"
)
#: Franka stroke handed to the forward pass as ``gripper_width``: its clamp keeps widths in
#: ``[0, gripper_width / 2]`` = [0, 8 cm].
_FORWARD_GRIPPER_WIDTH_M = 0.16


class LearnedExtraMissing(RuntimeError):
    """The optional ``learned`` extra (torch, cgn-pytorch, ...) is not importable."""


@dataclass(frozen=True)
class NetworkOutput:
    """One forward pass, in the frame the cloud was given in.

    Attributes:
        poses: (G, 4, 4) gripper-base poses (see :mod:`hsqbench.planner.learned.frames`).
        widths: (G,) predicted contact separation, metres.
        confidence: (G,) grasp success probability in [0, 1].
        input_index: (G,) index, into the cloud given, of the contact point of each grasp.
    """

    poses: NDArray[np.float64]
    widths: NDArray[np.float64]
    confidence: NDArray[np.float64]
    input_index: NDArray[np.int64]


def import_backend():
    """``(torch, fps, cgn_pytorch)``, or :class:`LearnedExtraMissing` saying how to install."""
    try:
        import cgn_pytorch
        import torch
        from torch_geometric.nn import fps
    except ImportError as exc:
        raise LearnedExtraMissing(f"{INSTALL_HINT} ({exc})") from exc
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
    _torch, _, cgn_pytorch = import_backend()
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
    keep = np.arange(cloud.shape[0])
    if keep.size > max_points:
        keep = np.sort(rng.choice(keep.size, size=max_points, replace=False))
    torch.manual_seed(seed)
    model = load_model(device)
    pcd = torch.as_tensor(cloud[keep], dtype=torch.float32, device=device)
    batch = torch.zeros(pcd.shape[0], dtype=torch.int64, device=device)
    with torch.no_grad():
        idx = fps(pcd, batch, min(1.0, 2048 / pcd.shape[0]))
        _, poses, logits, widths, _, _ = model(
            pcd[:, 3:],
            pcd_poses=pcd,
            batch=batch,
            idxs=idx,
            gripper_depth=depth_m,
            gripper_width=_FORWARD_GRIPPER_WIDTH_M,
        )
    return NetworkOutput(
        poses=poses.reshape(-1, 4, 4).cpu().numpy().astype(np.float64),
        widths=widths.reshape(-1).cpu().numpy().astype(np.float64),
        confidence=torch.sigmoid(logits).reshape(-1).cpu().numpy().astype(np.float64),
        input_index=keep[idx.cpu().numpy()],
    )
