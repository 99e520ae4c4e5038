"""The recorder: candidates charged to the stage that asked for them."""
from depthtrack.track.record import Recorder


def test_candidates_go_to_the_stage_that_asked_for_them():
    rec = Recorder()
    with rec.timed("render"):
        rec.count("candidates", 2)                      # the start's, before the snapshot
    assert rec.initialised()
    with rec.timed_excluding("search", "render"):      # the per-frame climb
        with rec.timed("render"):
            rec.count("candidates", 100)
    with rec.timed("heading"):                          # a recheck's climb is timed as search too
        with rec.timed_excluding("search", "render"):
            with rec.timed("render"):
                rec.count("candidates", 40)
    with rec.timed("polish"):
        with rec.timed("render"):
            rec.count("candidates", 10)
    rec.count("candidates", 1)                          # outside every stage
    summary = rec.timing_summary(total=1.0, frames=3)  # two tracked frames
    assert summary["candidates_per_frame"] == 75.5
    assert summary["candidates_per_frame_by_stage"] == {"search": 50.0, "heading": 20.0, "polish": 5.0,
                                                        "other": 0.5}
    assert summary["init_candidates"] == 2
    assert "polish" in summary["per_frame_ms"]
