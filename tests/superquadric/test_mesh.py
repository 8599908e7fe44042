"""Watertight triangle mesh (hsqbench.superquadric.mesh, through Superquadric.to_mesh)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.superquadric.examples import SHAPES, make


@pytest.mark.parametrize("name", sorted(SHAPES))
def test_mesh_is_watertight_on_surface_with_right_volume(name: str) -> None:
    sq = make(name, np.random.default_rng(13))
    mesh = sq.to_trimesh()
    assert mesh.is_watertight and mesh.is_winding_consistent
    np.testing.assert_allclose(sq.inside_outside(mesh.vertices), 1.0, rtol=1e-9)
    assert mesh.volume == pytest.approx(sq.volume, rel=0.005)  # positive: faces point outward
    vertices, faces = sq.to_mesh(8)
    assert faces.dtype.kind == "i" and faces.max() == vertices.shape[0] - 1


def test_mesh_rejects_coarse_resolution() -> None:
    with pytest.raises(ValueError, match="n_quarter"):
        make("sphere").to_mesh(1)
