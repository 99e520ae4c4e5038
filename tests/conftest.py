"""Shared test fixtures: where the project's shared mocap data lives, and the short synthetic
sequence the tracker's recovery, re-track and proposal tests share."""
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """``../shared/data`` beside the repository; tests that need it skip without it."""
    if not SHARED_DATA.is_dir():
        pytest.skip("../shared/data is not present")
    return SHARED_DATA


@pytest.fixture(scope="module")
def squat(tmp_path_factory):
    """15 frames of a half squat, arms forward (SR4000, ToF noise)."""
    from depthtrack.io import open_sequence
    from depthtrack.synth.generate import synthesize_procedural

    d = tmp_path_factory.mktemp("squat") / "seq"
    synthesize_procedural("squat", d, start=0.6, seconds=0.6, seed=3)
    return open_sequence(d)
