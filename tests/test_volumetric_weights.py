"""Our VGN and GIGA modules load the published state dicts exactly; a missing, corrupt or wrong
file is one clear error (needs torch; the weights from HSQ_MODELS_DIR, see .ci/run)."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from hsqbench.planner.learned import volumetric, weights

pytestmark = pytest.mark.skipif(
    not volumetric.available(),
    reason="torch is not installed (the optional 'learned' extra: pip install -e '.[learned]')",
)


def _published(network: str, training: str):
    try:
        return weights.weights_path(network, training, "unused", download=False)
    except weights.WeightsError as exc:
        pytest.skip(f"the published weights are not here ({exc}); set HSQ_MODELS_DIR")


def _modules():
    from hsqbench.planner.learned.giga_net import GIGANet
    from hsqbench.planner.learned.vgn_net import VGNNet

    return {"vgn": VGNNet, "giga": GIGANet}


@pytest.mark.parametrize("network", ["vgn", "giga"])
@pytest.mark.parametrize("training", ["packed", "pile"])
def test_state_dicts_load_with_every_key_and_shape(network, training):
    import torch

    path = _published(network, training)
    module = _modules()[network]()
    given = torch.load(path, map_location="cpu", weights_only=True)
    assert weights.state_dict_problems(module.state_dict(), given) == []
    loaded = weights.load_strict(module, path)
    for key, value in loaded.state_dict().items():
        assert torch.equal(value, given[key]), key
    expected_parameters = {"vgn": 313_238, "giga": 581_863}[network]  # the models' README
    assert sum(p.numel() for p in loaded.parameters()) == expected_parameters


def test_a_file_of_the_other_network_is_refused_naming_it():
    path = _published("giga", "packed")
    with pytest.raises(weights.WeightsError, match=r"giga_packed\.pt does not fit the VGNNet"):
        weights.load_strict(_modules()["vgn"](), path)


def test_a_missing_or_corrupt_file_is_one_clear_line(tmp_path, monkeypatch):
    published = _published("vgn", "packed")
    folder = tmp_path / weights.FOLDER
    folder.mkdir()
    monkeypatch.setenv("HSQ_MODELS_DIR", str(tmp_path))
    with pytest.raises(weights.WeightsError, match=r"vgn_packed\.pt is missing: HSQ_MODELS_DIR"):
        weights.weights_path("vgn", "packed", "unused")
    data = bytearray(published.read_bytes())
    data[1000] ^= 0xFF
    (folder / "vgn_packed.pt").write_bytes(bytes(data))
    with pytest.raises(weights.WeightsError) as info:
        weights.weights_path("vgn", "packed", "unused")
    message = str(info.value)
    assert "\n" not in message and "is not the published vgn_packed weights" in message
    shutil.copyfile(published, folder / "vgn_packed.pt")
    assert weights.weights_path("vgn", "packed", "unused") == folder / "vgn_packed.pt"


def test_scatter_mean_of_the_full_grid_is_the_mean_along_the_dropped_axis():
    """GIGA's plane features: every voxel of a 40^3 grid lands in the plane cell of its two
    coordinates, so the scatter mean is the mean along the third axis."""
    import torch

    from hsqbench.planner.learned import giga_net

    encoder = giga_net.PlaneEncoder().eval()
    captured = {}
    encoder.unet.forward = lambda plane: captured.setdefault(len(captured), plane)
    tsdf = torch.from_numpy(np.random.default_rng(0).random((1, 40, 40, 40), dtype=np.float32))
    with torch.no_grad():
        encoder(tsdf)
        feats = torch.relu(encoder.conv_in(tsdf[:, None]))  # (1, 32, X, Y, Z)
    # Planes are laid out [row = second axis, column = first axis].
    expected = {
        0: feats.mean(dim=3).transpose(2, 3),  # xz: mean over y, rows z, columns x
        1: feats.mean(dim=4).transpose(2, 3),  # xy: mean over z, rows y, columns x
        2: feats.mean(dim=2).transpose(2, 3),  # yz: mean over x, rows z, columns y
    }
    for n, plane in expected.items():
        torch.testing.assert_close(captured[n], plane, rtol=1e-5, atol=1e-6)
