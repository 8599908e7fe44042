"""The pure-torch fps, radius and knn that replace torch-cluster under torch-geometric, against
brute-force references written here, and against torch-cluster itself where it is installed."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="the learned extra is not installed (make learned)")

from hsqbench.planner.learned import cluster_ops  # noqa: E402  (imports torch)


def cloud(n: int, seed: int, scale: float = 0.3) -> torch.Tensor:
    return torch.as_tensor(np.random.default_rng(seed).random((n, 3)) * scale, dtype=torch.float32)


def reference_fps(points: np.ndarray, n_out: int, start: int) -> list[int]:
    """Textbook farthest point sampling in float32: each pick maximises the distance to the
    nearest earlier pick, ties to the lowest index."""
    nearest = np.full(len(points), np.inf, dtype=np.float32)
    picked = [start]
    for _ in range(1, n_out):
        diff = points - points[picked[-1]]
        nearest = np.minimum(nearest, (diff * diff).sum(1, dtype=np.float32))
        picked.append(int(np.argmax(nearest)))
    return picked


@pytest.mark.parametrize(("n", "ratio"), [(3000, 0.2), (997, 0.25), (500, 1.0)])
def test_fps_matches_the_textbook_algorithm(n, ratio):
    points = cloud(n, seed=n)
    got = cluster_ops.fps(points, None, ratio, random_start=False)
    n_out = int(np.ceil(np.float32(n) * np.float32(ratio)))
    assert got.tolist() == reference_fps(points.numpy(), n_out, 0)
    assert len(set(got.tolist())) == n_out  # no point twice


def test_fps_random_start_follows_torchs_seed():
    points = cloud(400, seed=1)
    torch.manual_seed(3)
    first = cluster_ops.fps(points, None, 0.1)
    torch.manual_seed(3)
    assert torch.equal(first, cluster_ops.fps(points, None, 0.1))
    starts = set()
    for seed in range(8):
        torch.manual_seed(seed)
        starts.add(int(cluster_ops.fps(points, None, 0.1)[0]))
    assert len(starts) > 1


def test_fps_samples_each_example_of_a_batch_on_its_own():
    a, b = cloud(300, seed=2), cloud(200, seed=3)
    batch = torch.cat([torch.zeros(300, dtype=torch.long), torch.ones(200, dtype=torch.long)])
    got = cluster_ops.fps(torch.cat([a, b]), batch, 0.1, random_start=False)
    assert got[:30].tolist() == reference_fps(a.numpy(), 30, 0)
    assert (got[30:] - 300).tolist() == reference_fps(b.numpy(), 20, 0)


def test_radius_keeps_the_first_neighbours_in_input_order():
    x, y = cloud(5000, seed=4), cloud(300, seed=5)
    r, cap = 0.03, 16  # about 21 points a ball: some hold more than cap, some fewer
    rows, cols = cluster_ops.radius(x, y, r, max_num_neighbors=cap)
    dist2 = ((y.numpy()[:, None] - x.numpy()[None]) ** 2).sum(-1)
    full = capped = 0
    for i in range(len(y)):
        inside = np.flatnonzero(dist2[i] < np.float32(r * r))
        assert cols[rows == i].tolist() == inside[:cap].tolist()
        full += len(inside) <= cap
        capped += len(inside) > cap
    assert full > 0 and capped > 0  # both cases were exercised
    assert torch.equal(rows, rows.sort().values)


def test_knn_returns_the_nearest_points_nearest_first():
    x, y = cloud(2000, seed=6), cloud(700, seed=7)
    rows, cols = cluster_ops.knn(x, y, 3)
    dist2 = ((y.numpy()[:, None] - x.numpy()[None]) ** 2).sum(-1)
    expected = np.argsort(dist2, axis=1, kind="stable")[:, :3]
    np.testing.assert_array_equal(rows.numpy(), np.repeat(np.arange(700), 3))
    np.testing.assert_array_equal(cols.numpy().reshape(700, 3), expected)


def test_batched_radius_and_knn_stay_within_each_example():
    x = torch.cat([cloud(400, seed=8), cloud(400, seed=9)])
    y = torch.cat([x[:50], x[400:450]])
    bx = torch.repeat_interleave(torch.arange(2), 400)
    by = torch.repeat_interleave(torch.arange(2), 50)
    for rows, cols in (
        cluster_ops.radius(x, y, 0.1, bx, by, max_num_neighbors=64),
        cluster_ops.knn(x, y, 4, bx, by),
    ):
        assert torch.equal(by[rows], bx[cols])
        assert set(rows.tolist()) == set(range(100))  # each centre finds itself at least


def test_unsorted_batches_and_cosine_are_refused():
    x = cloud(10, seed=10)
    with pytest.raises(ValueError, match="sorted"):
        cluster_ops.radius(x, x, 0.1, torch.tensor([1] * 5 + [0] * 5), torch.zeros(10).long())
    with pytest.raises(ValueError, match="cosine"):
        cluster_ops.knn(x, x, 2, cosine=True)
    with pytest.raises(ValueError, match="ratio"):
        cluster_ops.fps(x, None, 0.0)


def test_torch_geometric_runs_on_these_ops_once_installed():
    tg_nn = pytest.importorskip("torch_geometric.nn", reason="torch-geometric is not installed")
    cluster_ops.install()
    x, y = cloud(1500, seed=11), cloud(100, seed=12)
    assert torch.equal(
        tg_nn.fps(x, ratio=0.1, random_start=False), cluster_ops.fps(x, None, 0.1, False)
    )
    assert torch.equal(
        tg_nn.radius(x, y, 0.05, max_num_neighbors=8),
        cluster_ops.radius(x, y, 0.05, max_num_neighbors=8),
    )
    assert torch.equal(tg_nn.knn(x, y, 3), cluster_ops.knn(x, y, 3))


def test_same_results_as_torch_cluster_where_it_is_installed():
    """fps and knn give torch-cluster's indices; radius gives the same balls wherever a ball holds
    at most max_num_neighbors points (past that, torch-cluster's CPU code keeps a k-d tree's
    subset: see the module notes)."""
    torch_cluster = pytest.importorskip("torch_cluster", reason="torch-cluster is not installed")
    for seed in range(3):
        x, y = cloud(20000, seed=seed), cloud(400, seed=seed + 100)
        assert torch.equal(
            cluster_ops.fps(x, None, 2048 / 20000, False),
            torch_cluster.fps(x, None, 2048 / 20000, False),
        )
        assert torch.equal(cluster_ops.knn(x, y, 3), torch_cluster.knn(x, y, 3))
        ours = cluster_ops.radius(x, y, 0.01, max_num_neighbors=1000)
        theirs = torch_cluster.radius(x, y, 0.01, max_num_neighbors=1000)
        assert {tuple(p) for p in ours.T.tolist()} == {tuple(p) for p in theirs.T.tolist()}
