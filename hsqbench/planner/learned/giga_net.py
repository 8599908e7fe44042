"""GIGA's network (Jiang et al., RSS 2021): a tri-plane convolutional occupancy encoder on the
TSDF and four implicit decoders (grasp quality, orientation, width, occupancy).

Facts from the published state dict and GIGA's ConvONet configuration (``voxel_simple_local``
encoder, ``simple_local`` decoders, ``padding: 0``, ``c_dim: 32``, ``hidden_size: 32``,
``plane_resolution: 40``, U-Net depth 3 from 32 filters with concatenation):

- Encoder: a 3x3x3 convolution (1 -> 32 channels, ReLU) gives each voxel a feature. Voxel
  ``(i, j, k)`` of an ``n``-voxel side sits at ``-0.5 + i / (n - 1)`` (one unit = the cube);
  its feature is averaged (scatter mean) into one cell of each of the planes xz, xy, yz, the
  cell of its two coordinates mapped to ``[0, 1)`` and floored to 40 cells. Each plane then
  goes through one shared 2D U-Net: two 3x3 convolutions with ReLU per level (32, 64, 128
  channels; 2x2 max pooling between levels), transposed 2x2 convolutions back up, the skip
  connection concatenated before the level's two convolutions, and a final 1x1 convolution.
- Decoders: a query point ``p`` in ``[-0.5, 0.5)^3`` reads each plane bilinearly at its two
  coordinates (``align_corners``, border padding) and concatenates the three 32-channel
  features (xz, xy, yz: 96). Then ``net = fc_p(p)``; five times ``net += fc_c[n](feature)``
  followed by a fully connected ResNet block (``x + fc_1(relu(fc_0(relu(x))))``); the output
  is ``fc_out(relu(net))``. Quality goes through a sigmoid, the quaternion (x, y, z, w) is
  normalised, the width is in units of the cube's side, occupancy is a logit.

The scatter mean is written with ``index_add_`` (no torch-scatter).
"""

from __future__ import annotations

import itertools

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

#: Channels of one plane's feature, and of the decoders' hidden layers.
FEATURE_DIM = 32
HIDDEN = 32
PLANE_RESOLUTION = 40
#: Planes in the order their features are concatenated, with the two axes each one reads.
PLANES = (("xz", (0, 2)), ("xy", (0, 1)), ("yz", (1, 2)))
UNET_FILTERS = (32, 64, 128)
N_BLOCKS = 5
#: The networks' coordinate normalisation: divide by ``1 + padding + 1e-5`` (padding 0), shift
#: by 0.5, clamp below 1.
_NORMALISE = 1.0 + 10e-6
_BELOW_ONE = 1.0 - 10e-6
#: Output size of each decoder.
DECODERS = (("qual", 1), ("rot", 4), ("width", 1), ("tsdf", 1))


def _unit(p: torch.Tensor) -> torch.Tensor:
    """Coordinates in ``[-0.5, 0.5]`` to ``[0, 1)`` as the networks do."""
    return (p / _NORMALISE + 0.5).clamp(0.0, _BELOW_ONE)


def scatter_mean(values: torch.Tensor, index: torch.Tensor, size: int) -> torch.Tensor:
    """Mean of ``values`` (B, C, N) over the entries with equal ``index`` (N,) in [0, size):
    (B, C, size), 0 where no entry falls."""
    total = values.new_zeros(values.shape[0], values.shape[1], size)
    total.index_add_(2, index, values)
    count = torch.zeros(size, dtype=values.dtype, device=values.device)
    count.index_add_(0, index, torch.ones_like(index, dtype=values.dtype))
    return total / count.clamp(min=1.0)


class _Level(nn.Module):
    def __init__(self, c_in: int, c_out: int) -> None:
        super().__init__()
        self.conv1 = nn.Conv2d(c_in, c_out, 3, padding=1)
        self.conv2 = nn.Conv2d(c_out, c_out, 3, padding=1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return F.relu(self.conv2(F.relu(self.conv1(x))))


class _UpLevel(_Level):
    def __init__(self, c_in: int, c_out: int) -> None:
        super().__init__(2 * c_out, c_out)
        self.upconv = nn.ConvTranspose2d(c_in, c_out, 2, stride=2)

    def merge(self, skip: torch.Tensor, below: torch.Tensor) -> torch.Tensor:
        return self.forward(torch.cat((self.upconv(below), skip), dim=1))


class UNet2D(nn.Module):
    """The plane U-Net (state dict names ``down_convs``, ``up_convs``, ``conv_final``)."""

    def __init__(self, channels: int = FEATURE_DIM) -> None:
        super().__init__()
        ins = (channels, *UNET_FILTERS[:-1])
        self.down_convs = nn.ModuleList(
            _Level(a, b) for a, b in zip(ins, UNET_FILTERS, strict=True)
        )
        ups = UNET_FILTERS[::-1]
        self.up_convs = nn.ModuleList(_UpLevel(a, b) for a, b in itertools.pairwise(ups))
        self.conv_final = nn.Conv2d(UNET_FILTERS[0], channels, 1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        skips = []
        for n, level in enumerate(self.down_convs):
            x = level(x)
            if n < len(self.down_convs) - 1:
                skips.append(x)
                x = F.max_pool2d(x, 2)
        for level, skip in zip(self.up_convs, reversed(skips), strict=True):
            x = level.merge(skip, x)
        return self.conv_final(x)


class PlaneEncoder(nn.Module):
    """TSDF (B, n, n, n) -> one (B, 32, 40, 40) feature plane per entry of :data:`PLANES`."""

    def __init__(self) -> None:
        super().__init__()
        self.conv_in = nn.Conv3d(1, FEATURE_DIM, 3, padding=1)
        self.unet = UNet2D()

    def forward(self, tsdf: torch.Tensor) -> dict[str, torch.Tensor]:
        batch, n = tsdf.shape[0], tsdf.shape[1]
        features = F.relu(self.conv_in(tsdf[:, None])).reshape(batch, FEATURE_DIM, -1)
        side = torch.linspace(-0.5, 0.5, n, device=tsdf.device)
        grid = torch.stack(torch.meshgrid(side, side, side, indexing="ij"), dim=-1)
        cells = (_unit(grid.reshape(-1, 3)) * PLANE_RESOLUTION).long()
        planes = {}
        for name, (a, b) in PLANES:
            index = cells[:, a] + PLANE_RESOLUTION * cells[:, b]
            plane = scatter_mean(features, index, PLANE_RESOLUTION**2)
            plane = plane.reshape(batch, FEATURE_DIM, PLANE_RESOLUTION, PLANE_RESOLUTION)
            planes[name] = self.unet(plane)
        return planes


class ResnetBlockFC(nn.Module):
    def __init__(self, size: int) -> None:
        super().__init__()
        self.fc_0 = nn.Linear(size, size)
        self.fc_1 = nn.Linear(size, size)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.fc_1(F.relu(self.fc_0(F.relu(x))))


class LocalDecoder(nn.Module):
    """Query points (B, N, 3) and planes -> (B, N, out)."""

    def __init__(self, out_dim: int) -> None:
        super().__init__()
        c_dim = FEATURE_DIM * len(PLANES)
        self.fc_p = nn.Linear(3, HIDDEN)
        self.fc_c = nn.ModuleList(nn.Linear(c_dim, HIDDEN) for _ in range(N_BLOCKS))
        self.blocks = nn.ModuleList(ResnetBlockFC(HIDDEN) for _ in range(N_BLOCKS))
        self.fc_out = nn.Linear(HIDDEN, out_dim)

    def forward(self, points: torch.Tensor, feature: torch.Tensor) -> torch.Tensor:
        net = self.fc_p(points)
        for fc_c, block in zip(self.fc_c, self.blocks, strict=True):
            net = block(net + fc_c(feature))
        return self.fc_out(F.relu(net))


def sample_planes(points: torch.Tensor, planes: dict[str, torch.Tensor]) -> torch.Tensor:
    """(B, N, 96): each plane read bilinearly at the points' two coordinates, concatenated."""
    read = []
    for name, (a, b) in PLANES:
        uv = 2.0 * _unit(points[..., [a, b]]) - 1.0
        sampled = F.grid_sample(
            planes[name], uv[:, :, None], mode="bilinear", padding_mode="border", align_corners=True
        )
        read.append(sampled[..., 0])
    return torch.cat(read, dim=1).transpose(1, 2)


class GIGANet(nn.Module):
    """The GIGA network: :meth:`encode` a (B, 40, 40, 40) TSDF, then :meth:`decode` query
    points (B, N, 3) in ``[-0.5, 0.5)`` to quality (B, N), quaternion (B, N, 4) and width
    (B, N, in cube sides); :meth:`occupancy_logits` reads the fourth decoder."""

    def __init__(self) -> None:
        super().__init__()
        self.encoder = PlaneEncoder()
        for name, out_dim in DECODERS:
            self.add_module(f"decoder_{name}", LocalDecoder(out_dim))

    def encode(self, tsdf: torch.Tensor) -> dict[str, torch.Tensor]:
        if tsdf.ndim != 4 or tuple(tsdf.shape[1:]) != (PLANE_RESOLUTION,) * 3:
            raise ValueError(f"GIGA takes a (B, 40, 40, 40) grid, got {tuple(tsdf.shape)}")
        return self.encoder(tsdf)

    def decode(
        self, points: torch.Tensor, planes: dict[str, torch.Tensor]
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        feature = sample_planes(points, planes)
        quality = torch.sigmoid(self.decoder_qual(points, feature)[..., 0])
        rotation = F.normalize(self.decoder_rot(points, feature), dim=2)
        width = self.decoder_width(points, feature)[..., 0]
        return quality, rotation, width

    def occupancy_logits(
        self, points: torch.Tensor, planes: dict[str, torch.Tensor]
    ) -> torch.Tensor:
        return self.decoder_tsdf(points, sample_planes(points, planes))[..., 0]


@torch.no_grad()
def predict_giga(
    net: GIGANet, inputs: np.ndarray, needed: np.ndarray, device: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cubes ``inputs`` (T, 40, 40, 40) encoded in one pass, the decoders queried at the voxels
    ``needed`` (T, 40, 40, 40) only: quality (T, 40, 40, 40), quaternion (..., 4) as
    (x, y, z, w), width in voxels; 0 (quaternion (0, 0, 0, 1)) at the voxels not queried.

    Voxel ``i`` is queried at ``-0.5 + i / 40`` (GIGA's detection grid), so its output belongs to
    the position ``i`` voxels from the cube's corner."""
    x = torch.from_numpy(np.ascontiguousarray(inputs, dtype=np.float32)).to(device)
    planes = net.encode(x)
    n = inputs.shape[1]
    quality = np.zeros(inputs.shape)
    rotation = np.zeros((*inputs.shape, 4))
    rotation[..., 3] = 1.0
    width = np.zeros(inputs.shape)
    for t in range(inputs.shape[0]):  # one decoder pass per cube (a handful)
        index = np.argwhere(needed[t])
        if not len(index):
            continue
        points = torch.from_numpy((index / n - 0.5).astype(np.float32))[None].to(device)
        own = {k: v[t : t + 1] for k, v in planes.items()}
        q, r, w = net.decode(points, own)
        at = tuple(index.T)
        quality[(t, *at)] = q[0].cpu().double().numpy()
        rotation[(t, *at)] = r[0].cpu().double().numpy()
        width[(t, *at)] = w[0].cpu().double().numpy() * n
    return quality, rotation, width
