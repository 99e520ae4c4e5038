"""Shared test fixtures: where the project's shared mocap data lives, and the short synthetic
sequence the tracker's recovery, re-track and proposal tests share."""
from pathlib import Path

# first, before numpy: OpenBLAS's kernels pinned as for the command line, so that the tests'
# tracks are the same numbers on every x86-64 machine (depthtrack.environment)
import depthtrack  # noqa: F401

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"

#: Seconds the slowest test files took on a 2-core machine (``make test``'s ``--durations``,
#: summed per file; 2026-12-01, 802 s for the suite), longest first. ``make test`` runs
#: whole files per worker (``--dist loadfile``) in collection order
#: (``--no-loadscope-reorder``): xdist's own order, by number of tests, left the one- and
#: two-test tracker files, 80 s each, to the very end, one worker running them while the
#: other idled. Longest first, the last files to start are short and both workers finish
#: together. Files not named here run after these in their usual order; a stale figure
#: only costs balance, never a test.
SLOW_FILES = {
    "test_track_revoke.py": 243, "test_track_recovery.py": 190,
    "test_track_final_polish.py": 175, "test_track_tracker.py": 111, "test_track_bends.py": 107,
    "test_track_shape_fit.py": 87, "test_track_facing.py": 85, "test_track_retrack.py": 79,
    "test_track_reference.py": 69, "test_track_start_waits.py": 67,
    "test_track_proposals.py": 61, "test_track_stream_gl.py": 48, "test_kill.py": 43,
    "test_batch.py": 43, "test_track_limb_prior.py": 35, "test_track_carry_back.py": 28,
    "test_track_start_grid.py": 21, "test_demo.py": 19,
}


def pytest_collection_modifyitems(items):
    """The slowest files first (a stable sort: each file's tests stay together, in order)."""
    items.sort(key=lambda item: -SLOW_FILES.get(item.path.name, 0))


@pytest.fixture(autouse=True)
def _final_polish_only_where_asked(request, monkeypatch):
    """The tracker's final polish (``PolishSettings.final_tile``) is off in tests not marked
    ``final_polish``. It changes no decision of a track -- ``test_track_final_polish.py``
    tracks with and without it, a heading switch, its re-track and revoke included, and
    finds every frame's energy alike -- and it adds a third to each tracked frame's time
    (the whole suite about 50 s), which the tests of the decisions do not need. Commands run as subprocesses
    (``depthtrack track``, the demo) still run the default tracker, final polish included."""
    if request.node.get_closest_marker("final_polish") is not None:
        return
    import dataclasses

    from depthtrack.track.settings import PolishSettings

    defaults = tuple(0 if f.name == "final_tile" else f.default
                     for f in dataclasses.fields(PolishSettings))
    monkeypatch.setattr(PolishSettings.__init__, "__defaults__", defaults)


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


class FirstFrames:
    """The first ``n`` frames of a sequence: what a tracker and a test read of one (``len``,
    ``depth(i)``, ``joints``, ``camera``, ``fps``), the frames themselves unchanged."""

    def __init__(self, seq, n: int):
        if not 0 < n <= len(seq):
            raise ValueError(f"{n} frames of a sequence of {len(seq)}")
        self.seq, self.n = seq, int(n)
        self.camera, self.fps = seq.camera, seq.fps

    def __len__(self) -> int:
        return self.n

    def depth(self, i: int):
        if not 0 <= i < self.n:
            raise IndexError(f"frame {i} of {self.n}")
        return self.seq.depth(i)

    @property
    def joints(self):
        return self.seq.joints[:self.n]


@pytest.fixture(scope="module")
def squat12(squat):
    """The squat's first 12 frames: enough for the tests whose corrections land by frame 8
    or 10 (the rechecks every 4 frames; the flip search every 5), a fifth less tracking."""
    return FirstFrames(squat, 12)
