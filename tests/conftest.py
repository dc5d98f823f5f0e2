"""Shared fixtures: paths to the real sample assets, a scratch copy of them, one model cache for the
whole session, and torch on one thread for the tiny networks."""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SAMPLES = REPO / "sample_assets"


@pytest.fixture(scope="session")
def samples_dir() -> Path:
    return SAMPLES


@pytest.fixture()
def samples_copy(tmp_path: Path) -> Path:
    """A private copy of ``sample_assets/`` that a test may write next to."""
    dst = tmp_path / "sample_assets"
    shutil.copytree(SAMPLES, dst)
    return dst


@pytest.fixture(scope="session")
def model_cache(tmp_path_factory) -> Path:
    """One model and tile cache for the whole session: a stack processed by several tests trains once.

    Tests about the cache itself (cold runs, resume, concurrent runs) use a folder of their own."""
    return tmp_path_factory.mktemp("model-cache")


@pytest.fixture(scope="module")
def one_thread():
    """Torch on one thread for a module: tiny networks run fastest (and steadiest on a shared
    machine) that way. Modules opt in with ``pytestmark = pytest.mark.usefixtures("one_thread")``."""
    import torch

    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)
