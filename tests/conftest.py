"""Shared fixtures: paths to the real sample assets and a scratch copy of them."""
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
