"""Pure-torch farthest point sampling, radius and k-nearest-neighbour search for torch-geometric.

cgn-pytorch's PointNet++ calls ``torch_geometric.nn.fps``, ``radius`` and (through
``knn_interpolate``) ``knn``; torch-geometric 2.4 hands all three to the ``torch_cluster``
package, which has no binary wheel on PyPI and takes 11 minutes (idle) to 30 (loaded) to compile
on two cores. :func:`install` points torch-geometric's pooling module at this module instead,
whether or not torch-cluster is installed, so every machine runs the same code. Nothing else of
torch-geometric is touched, and ``sys.modules`` is not.

The functions take torch-cluster 1.6.3's arguments and return what it returns:

- :func:`fps` runs torch-cluster's CPU algorithm with the same tensor operations (farthest from
  the points picked so far, ties to the lowest index, ``ceil(ratio * n)`` points in float32), so
  its indices are identical. ``random_start=True`` draws the start from torch's generator (seeded
  by ``torch.manual_seed``; torch-cluster's CPU code used C's ``rand()``, which no seed reached).
- :func:`knn`: the ``k`` nearest points of ``x`` for each point of ``y``, nearest first (exact, as
  torch-cluster's k-d tree is).
- :func:`radius`: the points of ``x`` closer than ``r`` to each point of ``y``, at most
  ``max_num_neighbors`` of them: the first ones in the order of ``x``. This is torch-cluster's CUDA
  kernel (and PointNet++'s ball query); its CPU code keeps the first ones its k-d tree visits
  instead, a spatially biased subset. Where a ball holds at most ``max_num_neighbors`` points the
  two agree; where it holds more, the subsets differ (the module notes of :mod:`.network`).

Distances are brute force, in chunks of ``_CHUNK_ELEMENTS`` query-point pairs (a 20 000-point
cloud against 2 048 centres is 41 M pairs; a chunk holds 4 M, 16 MB of float32).
"""

from __future__ import annotations

import torch

#: Query-point pairs per distance chunk (bounds the memory of one chunk to ~16 MB of float32).
_CHUNK_ELEMENTS = 1 << 22


def install() -> None:
    """Make torch-geometric's ``fps``, ``radius`` and ``knn`` (and ``knn_interpolate``) use this
    module. They look ``torch_cluster`` up in their module at each call, so this works before
    or after cgn-pytorch is imported."""
    import sys

    import torch_geometric.nn.pool as pool

    pool.torch_cluster = sys.modules[__name__]


def _examples(
    batch_x: torch.Tensor | None, batch_y: torch.Tensor | None, n_x: int, n_y: int
) -> list[tuple[slice, slice]]:
    """``(x rows, y rows)`` of each example; examples are contiguous, as torch-cluster requires."""
    if batch_x is None and batch_y is None:
        return [(slice(0, n_x), slice(0, n_y))]
    if batch_x is None or batch_y is None:
        raise ValueError("give both batch_x and batch_y, or neither")
    if bool((batch_x[1:] < batch_x[:-1]).any()) or bool((batch_y[1:] < batch_y[:-1]).any()):
        raise ValueError("batch vectors must be sorted (each example's points contiguous)")
    n_examples = int(max(batch_x.max(), batch_y.max())) + 1 if n_x and n_y else 0
    ids = torch.arange(n_examples + 1, device=batch_x.device)
    ptr_x = torch.bucketize(ids, batch_x).tolist()
    ptr_y = torch.bucketize(ids, batch_y).tolist()
    return [
        (slice(ptr_x[b], ptr_x[b + 1]), slice(ptr_y[b], ptr_y[b + 1])) for b in range(n_examples)
    ]


def _squared_distances(y: torch.Tensor, x: torch.Tensor) -> torch.Tensor:
    """(len(y), len(x)) squared distances, summed over coordinates in order (as torch-cluster;
    one coordinate at a time: 3x faster than one (len(y), len(x), D) tensor, the same bits)."""
    dist = (y[:, 0, None] - x[:, 0]).square_()
    for c in range(1, y.shape[1]):
        dist += (y[:, c, None] - x[:, c]).square_()
    return dist


def _distances_to(columns: torch.Tensor, i: int) -> torch.Tensor:
    """(N,) squared distances to point ``i`` of a (D, N) coordinate-major cloud (same bits)."""
    dist = (columns[0] - columns[0, i]).square_()
    for c in range(1, columns.shape[0]):
        dist += (columns[c] - columns[c, i]).square_()
    return dist


def _chunks(n_y: int, n_x: int) -> list[slice]:
    step = max(1, _CHUNK_ELEMENTS // max(1, n_x))
    return [slice(start, min(start + step, n_y)) for start in range(0, n_y, step)]


def fps(
    src: torch.Tensor,
    batch: torch.Tensor | None = None,
    ratio: float = 0.5,
    random_start: bool = True,
    batch_size: int | None = None,
) -> torch.Tensor:
    """Indices into ``src`` (N, D) of ``ceil(ratio * n)`` farthest points of each example."""
    if not 0.0 < ratio <= 1.0:
        raise ValueError(f"fps ratio must lie in (0, 1], got {ratio}")
    src = src.reshape(src.shape[0], -1)
    if batch is None:
        batch = torch.zeros(src.shape[0], dtype=torch.long, device=src.device)
    out = []
    for rows, _ in _examples(batch, batch, src.shape[0], src.shape[0]):
        y = src[rows]
        n_out = int(torch.ceil(torch.tensor(float(y.shape[0])) * torch.tensor(ratio)).item())
        start = int(torch.randint(y.shape[0], ())) if random_start else 0
        columns = y.T.contiguous()  # one coordinate at a time (see _squared_distances)
        picked = [start]
        dist = _distances_to(columns, start)
        for _ in range(1, n_out):  # sequential by definition: each pick depends on the last
            picked.append(int(dist.argmax()))  # the first of equal maxima, as torch-cluster
            torch.minimum(dist, _distances_to(columns, picked[-1]), out=dist)
        out.append(torch.tensor(picked, dtype=torch.long, device=src.device) + rows.start)
    return torch.cat(out) if out else torch.empty(0, dtype=torch.long, device=src.device)


def radius(
    x: torch.Tensor,
    y: torch.Tensor,
    r: float,
    batch_x: torch.Tensor | None = None,
    batch_y: torch.Tensor | None = None,
    max_num_neighbors: int = 32,
    num_workers: int = 1,
    batch_size: int | None = None,
) -> torch.Tensor:
    """(2, E) ``[index into y, index into x]`` of the points of ``x`` within ``r`` of each point
    of ``y`` (at most ``max_num_neighbors``, the first in ``x``'s order), sorted by ``y``."""
    x, y = x.reshape(x.shape[0], -1), y.reshape(y.shape[0], -1)
    pairs = []
    for rows_x, rows_y in _examples(batch_x, batch_y, x.shape[0], y.shape[0]):
        xs, ys = x[rows_x], y[rows_y]
        for chunk in _chunks(ys.shape[0], xs.shape[0]):
            within = _squared_distances(ys[chunk], xs) < r * r
            rank = within.to(torch.int32).cumsum(1, dtype=torch.int32)  # 1-based, in x's order
            keep = within & (rank <= max_num_neighbors)
            row, col = keep.nonzero(as_tuple=True)
            pairs.append(torch.stack([row + chunk.start + rows_y.start, col + rows_x.start]))
    return torch.cat(pairs, 1) if pairs else torch.empty(2, 0, dtype=torch.long, device=x.device)


def knn(
    x: torch.Tensor,
    y: torch.Tensor,
    k: int,
    batch_x: torch.Tensor | None = None,
    batch_y: torch.Tensor | None = None,
    cosine: bool = False,
    num_workers: int = 1,
    batch_size: int | None = None,
) -> torch.Tensor:
    """(2, E) ``[index into y, index into x]`` of the ``k`` nearest points of ``x`` to each point
    of ``y`` (fewer where the example has fewer), nearest first, sorted by ``y``."""
    if cosine:
        raise ValueError("knn: the cosine distance is not implemented (cgn-pytorch never asks)")
    x, y = x.reshape(x.shape[0], -1), y.reshape(y.shape[0], -1)
    pairs = []
    for rows_x, rows_y in _examples(batch_x, batch_y, x.shape[0], y.shape[0]):
        xs, ys = x[rows_x], y[rows_y]
        k_here = min(k, xs.shape[0])
        for chunk in _chunks(ys.shape[0], xs.shape[0]):
            if k_here == 0:
                break
            _, col = _squared_distances(ys[chunk], xs).topk(k_here, dim=1, largest=False)
            row = torch.arange(chunk.start, chunk.stop, device=x.device).repeat_interleave(k_here)
            pairs.append(torch.stack([row + rows_y.start, col.reshape(-1) + rows_x.start]))
    return torch.cat(pairs, 1) if pairs else torch.empty(2, 0, dtype=torch.long, device=x.device)
