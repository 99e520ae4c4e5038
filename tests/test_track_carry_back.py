"""The shape-fit trial's later side corrections carried back to the frames before them."""
import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.body.skeleton import POSE_INDEX
from depthtrack.track.carry_back import (carried_twins, corrections_of, exchange_order,
                                         exchanged_after)
from depthtrack.track.twins import ARMS_SWAPPED, LEGS_SWAPPED, SIDES_SWAPPED, TWIN_ORDERS, facing_direction


@pytest.fixture(scope="module")
def squat(tmp_path_factory):
    """A noise-free SR4000 squat of five frames (the template body), for the GL tests."""
    render = pytest.importorskip("depthtrack.render")
    try:
        render.gl_context()
    except render.GLUnavailableError as exc:
        pytest.skip(f"no OpenGL: {exc}")
    from depthtrack.synth.generate import synthesize
    from depthtrack.synth.procedural import procedural_motion

    body = BodyModel.default(1.75)
    out = tmp_path_factory.mktemp("carry") / "seq"
    synthesize(out, body, procedural_motion("squat", body, 25.0)[40:70:6], 25.0,
               camera="sr4000", noise="none", subject={"height_m": 1.75})
    return out


def test_a_frame_carries_the_kinds_corrected_an_odd_number_of_times_after_it():
    described = {"heading_switches": [{"index": 12}, {"index": 5}],
                 "limb_swaps": [{"index": 8, "limbs": "legs"}]}
    corrections = corrections_of(described)
    assert corrections == [(5, "heading"), (8, "legs"), (12, "heading")]
    assert exchanged_after(0, corrections) == {"legs"}             # heading twice: back as it was
    assert exchanged_after(6, corrections) == {"legs", "heading"}
    assert exchanged_after(5, corrections) == {"legs", "heading"}  # frame 5's own switch holds there
    assert exchanged_after(12, corrections) == frozenset()
    # a recovery on frame 7 cuts the track: what came after says nothing of frame 0
    assert exchanged_after(0, corrections, cuts=[7]) == {"heading"}
    assert exchanged_after(0, corrections, cuts=[3]) == frozenset()


def test_the_exchanges_compose_as_the_heading_twins_orders():
    assert exchange_order({"heading"}) == list(SIDES_SWAPPED)
    assert exchange_order({"legs"}) == list(LEGS_SWAPPED)
    # turned with the legs where they are: the heading recheck's "all_but_legs" twin
    assert exchange_order({"heading", "legs"}) == list(TWIN_ORDERS["all_but_legs"])
    for kinds in ({"heading"}, {"legs"}, {"arms"}, {"heading", "arms"}):
        order = np.array(exchange_order(kinds))
        assert np.array_equal(order[order], np.arange(len(order)))   # an exchange undoes itself
    assert exchange_order({"arms", "legs"}) == list(np.array(ARMS_SWAPPED)[LEGS_SWAPPED])


def test_a_carried_twin_puts_each_joint_where_the_other_sides_was():
    body = BodyModel.default(1.75)
    pose = np.zeros(body.dof)
    pose[2] = 3.0
    for name, value in (("l_hip_rx", -0.4), ("l_knee_rx", 0.6), ("r_shoulder_rx", -0.5),
                        ("r_elbow_rx", -0.6)):
        pose[POSE_INDEX[name]] = value
    joints = np.asarray(body.joint_positions(pose))
    # (an arms' exchange is left out: this pose's hands are a shoulder width apart, out of
    # an upper arm's reach from the other side)
    for kinds in ({"heading"}, {"legs"}, {"heading", "legs"}):
        order = exchange_order(kinds)
        moved = np.flatnonzero(np.array(order) != np.arange(len(order)))
        twins = carried_twins(body, pose, kinds, ("turned", "rest"))
        best = min(twins, key=lambda t: np.linalg.norm(
            np.asarray(body.joint_positions(t)) - joints[order], axis=1).mean())
        got = np.asarray(body.joint_positions(best))
        # each exchanged joint nearer the other side's place than its own
        to_other = np.linalg.norm(got[moved] - joints[order][moved], axis=1)
        to_own = np.linalg.norm(got[moved] - joints[moved], axis=1)
        assert np.median(to_other) < 0.04 and to_other.mean() < to_own.mean(), kinds
        turned = facing_direction(best) @ facing_direction(pose)
        assert (turned < -0.5) if "heading" in kinds else (turned > 0.95), kinds
    # the limbs' twin starts from the pose itself: one fit, not one per start
    assert len(carried_twins(body, pose, {"arms"}, ("turned", "rest"))) == 1


def test_which_corrections_are_carried_back_is_a_checked_setting():
    from depthtrack.errors import InputError
    from depthtrack.track import ShapeSettings, TrackerSettings

    assert TrackerSettings().updated({"shape": {"carry_back": ["heading", "legs"]}}
                                     ).shape.carry_back == ("heading", "legs")
    assert ShapeSettings(carry_back="arms").carry_back == ("arms",)
    for bad in (True, ["heading", "elbows"]):
        with pytest.raises(InputError, match="carry_back"):
            ShapeSettings(carry_back=bad)


def test_the_trials_heading_switch_turns_the_fit_frames_and_the_start_before_it(monkeypatch,
                                                                                 squat):
    """A heading switch the trial makes on its third frame (forced, the pose turned to its
    twin as a recheck would) is carried back: the fit frames before it and the frame-0 pose
    the track takes over face as the trial did after the switch."""
    from depthtrack.io.sequence import open_sequence
    from depthtrack.track import ShapeSettings, TrackerSettings
    from depthtrack.track import rechecks as rechecks_module
    from depthtrack.track.twins import swapped_twin
    from depthtrack.track.height import fit_body_shape

    body = BodyModel.default(1.75)
    seq = open_sequence(squat)
    original = rechecks_module.recheck_heading

    def forced(state, pose, refit, twins, pixels, settings, **given):
        if state.frame == 2 and not state.heading_switches:
            switch = {"frame": state.frame, "by": "votes", "energy_kept": 2.0,
                      "energy_turned": 1.0}
            return (swapped_twin(body, pose),
                    {"heading_switches": state.heading_switches + (switch,)}, True)
        return original(state, pose, refit, twins, pixels, settings, **given)

    monkeypatch.setattr(rechecks_module, "recheck_heading", forced)
    runs = {}
    for carry in ((), ("heading",)):
        settings = TrackerSettings(heading={"frames": 0}, start={"complete_fraction": 0.0},
                                   energy={"prior_huber": 0.0},
                                   shape=ShapeSettings(frames=4, fit_frames=4, rounds=1,
                                                       max_iterations=1, prior_weight=1.0,
                                                       carry_back=carry))
        _, runs[carry] = fit_body_shape((seq.depth(i) for i in range(len(seq))), body,
                                        seq.camera, fps=seq.fps, settings=settings,
                                        fit_scale=False, method="hc")
    kept, carried = runs[()], runs[("heading",)]
    switch = carried["trial_heading_switches"][0]["index"]
    assert switch == 2
    assert "trial_carried_back" not in kept
    assert carried["trial_carried_back"] == [{"index": i, "exchanged": ["heading"]}
                                             for i in carried["frames_used"] if i < switch]
    # the start the track takes over faces the way the trial did after its switch
    before = facing_direction(np.array(kept["start_pose"]))
    after = facing_direction(np.array(carried["start_pose"]))
    assert before @ after < -0.5
    # and its joints stay where the frame shows them (the sides exchanged)
    truth = np.asarray(seq.joints[0])
    joints = np.asarray(body.joint_positions(np.array(carried["start_pose"])))
    assert np.median(np.linalg.norm(joints[SIDES_SWAPPED] - truth, axis=1)) < 0.06


def test_the_trial_sides_tool_reports_each_frames_facing(squat, tmp_path, capsys):
    """``tools/trial_sides.py``: the shape fit's trial on a noise-free squat faces the
    camera as the truth does on every frame; a sequence without ground truth is refused
    with one line and status 2."""
    import shutil

    from tool_module import load_tool

    tool = load_tool("trial_sides")
    seq = tmp_path / "seq"
    shutil.copytree(squat, seq)       # its ground truth is removed below
    out = tmp_path / "trial.json"
    settings = '{"shape": {"frames": 4}, "heading": {"frames": 0}, "energy": {"prior_huber": 0.0}}'
    assert tool.main([str(seq), "--settings", settings, "--json", str(out)]) == 0
    import json
    got = json.loads(out.read_text())[str(seq)]
    assert got["frames"] == [0, 1, 2, 3]
    assert max(got["facing_error_deg"]) < 30 and not any(got["legs_exchanged"])
    assert "facing" in capsys.readouterr().out
    (seq / "groundtruth" / "joints.csv").unlink()
    assert tool.main([str(seq)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "ground truth" in err[0]
