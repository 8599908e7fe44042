"""Every test sees an empty hsqbench data folder (HSQ_DATA_DIR), whatever this machine holds in
its download folder, so results never depend on what an earlier command downloaded."""

from __future__ import annotations

import pytest


@pytest.fixture(autouse=True)
def _empty_data_folder(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("HSQ_DATA_DIR", str(tmp_path_factory.mktemp("hsq-data")))
    monkeypatch.delenv("HSQ_YCB_URL", raising=False)
