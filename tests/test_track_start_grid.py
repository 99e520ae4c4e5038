"""The start's grid heard beside the recogniser's fits (``StartSettings.grid_heard``): on a
frame where the recogniser's fits fill the shortlist before any climb (a side step, legs
apart, its fits with the legs crossed), the grid's best is climbed too and wins on its score."""
import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.errors import InputError
from depthtrack.track import TrackerSettings
from depthtrack.track.tracker import Tracker


@pytest.fixture(scope="module")
def sidestep(tmp_path_factory):
    """A procedural side step from 3.5 s, 2 s at 25 fps, SR4000, ToF noise seed 2 (the
    synthesizer places the camera for the whole window; only frame 0 is tracked)."""
    from depthtrack.io import open_sequence
    from depthtrack.synth.generate import synthesize_procedural

    d = tmp_path_factory.mktemp("sidestep") / "seq"
    synthesize_procedural("sidestep", d, start=3.5, seconds=2.0, seed=2)
    return open_sequence(d)


def _start(seq, grid_heard):
    """``(joint errors (15,) m, init_info)`` of the automatic start on frame 0."""
    body = BodyModel.default(height=1.75)
    settings = TrackerSettings(shape={"enabled": False}).updated({"start": {"grid_heard": grid_heard}})
    with Tracker(body, seq.camera, fps=seq.fps, settings=settings) as tracker:
        tracker.init(seq.depth(0))
        info = tracker.init_info
        pose = tracker.pose
    return np.linalg.norm(body.joint_positions(pose) - seq.joints[0], axis=-1), info


def test_the_grid_is_heard_where_the_recognisers_fits_fill_the_finalists(sidestep):
    err_never, never = _start(sidestep, "never")
    err_heard, heard = _start(sidestep, "start")
    # without it every finalist is one of the recogniser's fits, and the start is off
    assert {f["from"] for f in never["finalists"]} == {"proposals"}
    assert never["chosen_from"] == "proposals" and err_never.max() > 0.15
    # with it the same finalists and the grid's best on top of them, which scores best
    assert heard["finalists"][:-1] == never["finalists"]
    assert heard["finalists"][-1]["from"] == "grid"
    assert heard["chosen_from"] == "grid"
    assert heard["finalists"][-1]["score"] == min(f["score"] for f in heard["finalists"])
    assert err_heard.max() < 0.1
    # the recogniser's best start it displaced, for the front/back check to hear
    # (StartSettings.displaced_checked)
    # (two of the recogniser's finalists can tie at the scores' 0.1 rounding: on one
    # machine 961 and 970 both list 4017.6, and the unrounded best is either, by the last
    # bits of the renderer's sums)
    best = min(f["score"] for f in heard["finalists"] if f["from"] == "proposals")
    ours = {f["candidate"] for f in heard["finalists"]
            if f["from"] == "proposals" and f["score"] == best}
    assert "displaced" not in never
    assert heard["displaced"]["candidate"] in ours and heard["displaced"]["from"] == "proposals"
    assert heard["displaced"]["score"] == best and len(heard["displaced"]["pose"]) == 48


def test_grid_heard_takes_the_searches_named_and_refuses_others():
    assert TrackerSettings().start.grid_heard == "never"
    for value in ("never", "start", "recovery", "always"):
        assert TrackerSettings().updated({"start": {"grid_heard": value}}).start.grid_heard == value
    with pytest.raises(InputError, match="grid_heard"):
        TrackerSettings().updated({"start": {"grid_heard": "sometimes"}})
    assert TrackerSettings().start.displaced_checked is False
    assert TrackerSettings().updated({"start": {"displaced_checked": True}}).start.displaced_checked
    with pytest.raises(InputError, match="displaced_checked"):
        TrackerSettings().updated({"start": {"displaced_checked": "yes"}})


def test_start_gate_says_which_start_the_grid_displaced(sidestep, capsys):
    """``tools/start_gate.py`` with ``grid_heard`` "start" is the start screen: its line says
    the grid won and how right the start it displaced was (the recogniser's, legs crossed)."""
    import json

    from tool_module import load_tool

    tool = load_tool("start_gate")
    assert tool.main([str(sidestep.path), "--settings", '{"start": {"grid_heard": "start"}}']) == 0
    line = json.loads(capsys.readouterr().out)
    assert line["chosen_from"] == "grid" and line["within_10cm"] == 1.0
    assert line["displaced"]["from"] == "proposals" and line["displaced"]["within_10cm"] < 0.9
    assert line["displaced"]["score"] > min(line["straight"])
    assert tool.main([str(sidestep.path)]) == 0            # "never": nothing displaced
    line = json.loads(capsys.readouterr().out)
    assert line["chosen_from"] == "proposals" and "displaced" not in line


def test_searched_in_maps_each_setting_onto_its_searches():
    start = TrackerSettings().updated({"start": {"legs": "recovery", "bends": "start",
                                                 "grid_heard": "always"}}).start
    assert start.searched_in("start") == {"legs": False, "bends": True, "grid_heard": True}
    assert start.searched_in("recovery") == {"legs": True, "bends": False, "grid_heard": True}
    default = TrackerSettings().start           # legs "never", bends "always"
    assert default.searched_in("start") == {"legs": False, "bends": True, "grid_heard": False}
