"""VGN's network (Breyer et al., CoRL 2020): a 3D convolutional encoder-decoder on the TSDF.

Layer sizes, from the published state dict and the paper: an encoder of three stride-2
convolutions (1 -> 16 -> 32 -> 64 channels, kernels 5, 3, 3: 40^3 -> 5^3), a decoder of three
convolutions (64 -> 64 -> 32 -> 16, kernels 3, 3, 5) each followed by nearest-neighbour
upsampling by two (back to 40^3), ReLU after every convolution, and three heads of kernel 5:
grasp quality (sigmoid), orientation (a quaternion x, y, z, w, normalised) and opening width
(in voxels, unbounded). Every convolution pads by half its kernel.

The published decoder upsamples to fixed sizes (10, 20, 40); upsampling by two is the same on a
40^3 grid and lets the network run on any grid whose sides are multiples of 8.
"""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

#: (channels, kernel) of the encoder's and decoder's convolutions, from the state dict.
ENCODER = ((16, 5), (32, 3), (64, 3))
DECODER = ((64, 3), (32, 3), (16, 5))
HEAD_KERNEL = 5


def _conv(c_in: int, c_out: int, kernel: int, stride: int = 1) -> nn.Conv3d:
    return nn.Conv3d(c_in, c_out, kernel, stride=stride, padding=kernel // 2)


class _Stage(nn.Module):
    """Three convolutions under the state dict's names ``conv1..conv3``."""

    def __init__(self, c_in: int, layers: tuple[tuple[int, int], ...], stride: int) -> None:
        super().__init__()
        for n, (c_out, kernel) in enumerate(layers, start=1):
            self.add_module(f"conv{n}", _conv(c_in, c_out, kernel, stride))
            c_in = c_out
        self.convs = [getattr(self, f"conv{n}") for n in range(1, len(layers) + 1)]


class VGNNet(nn.Module):
    """The VGN network; ``forward`` maps a (B, 1, X, Y, Z) TSDF (the read-out of
    :meth:`~hsqbench.planner.learned.tsdf.TSDFGrid.network_input`) to quality (B, X, Y, Z),
    quaternion (B, 4, X, Y, Z) and width in voxels (B, X, Y, Z)."""

    def __init__(self) -> None:
        super().__init__()
        self.encoder = _Stage(1, ENCODER, stride=2)
        self.decoder = _Stage(ENCODER[-1][0], DECODER, stride=1)
        width = DECODER[-1][0]
        self.conv_qual = _conv(width, 1, HEAD_KERNEL)
        self.conv_rot = _conv(width, 4, HEAD_KERNEL)
        self.conv_width = _conv(width, 1, HEAD_KERNEL)

    def forward(self, tsdf: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        if tsdf.ndim != 5 or any(n % 8 for n in tsdf.shape[2:]):
            raise ValueError(
                f"VGN takes a (B, 1, X, Y, Z) grid with sides multiple of 8, got {tuple(tsdf.shape)}"
            )
        x = tsdf
        for conv in self.encoder.convs:
            x = F.relu(conv(x))
        for conv in self.decoder.convs:
            x = F.interpolate(F.relu(conv(x)), scale_factor=2, mode="nearest")
        quality = torch.sigmoid(self.conv_qual(x))[:, 0]
        rotation = F.normalize(self.conv_rot(x), dim=1)
        width = self.conv_width(x)[:, 0]
        return quality, rotation, width


@torch.no_grad()
def predict_vgn(
    net: VGNNet, inputs: np.ndarray, device: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One pass over cubes ``inputs`` (T, X, Y, Z): quality (T, X, Y, Z), quaternion
    (T, X, Y, Z, 4) as (x, y, z, w), width in voxels (T, X, Y, Z), as float64 numpy."""
    x = torch.from_numpy(np.ascontiguousarray(inputs, dtype=np.float32))[:, None].to(device)
    quality, rotation, width = net(x)
    return (
        quality.cpu().double().numpy(),
        rotation.permute(0, 2, 3, 4, 1).cpu().double().numpy(),
        width.cpu().double().numpy(),
    )
