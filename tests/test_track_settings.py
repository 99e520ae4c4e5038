"""Tracker settings: one group per stage, validated at construction, serialised whole."""
import json

import pytest

from depthtrack.errors import InputError
from depthtrack.track import (AssociateSettings, HeadingSettings, SearchSettings, StartSettings,
                              TrackerSettings)
from depthtrack.track.settings import FLAT_NAMES, GROUPS


def test_flat_names_construct_and_read_through_their_groups():
    s = TrackerSettings(heading_frames=0, lost_ratio=2.0, init_passes=4)
    assert s.heading == HeadingSettings(frames=0) and s.heading_frames == 0
    assert s.judge.lost_ratio == 2.0 and s.lost_ratio == 2.0
    assert s.start.passes == 4
    assert TrackerSettings() == TrackerSettings(search=SearchSettings())
    assert s.replace(passes=3).search.passes == 3 and s.replace(passes=3).heading.frames == 0


@pytest.mark.parametrize("kwargs", [
    {"accept": "likelihod"}, {"refine_scope": "arm"}, {"tile": 48}, {"fine_tile": 100},
    {"absent_frames": 0}, {"lost_ratio": -1.0}, {"no_such_setting": 1}, {"heading_margin": -0.1},
])
def test_bad_values_are_refused_when_made(kwargs):
    with pytest.raises(InputError):
        TrackerSettings(**kwargs)


def test_groups_are_frozen_and_checked_on_their_own():
    with pytest.raises(InputError):
        AssociateSettings(accept="energy")
    with pytest.raises(InputError):
        HeadingSettings(recheck_tile=48)
    with pytest.raises(InputError):
        TrackerSettings(shape={"trial_rechecks": "no"})
    s = TrackerSettings()
    with pytest.raises(Exception):
        s.search.passes = 5                     # frozen: a stage cannot switch modes in place


def test_every_schedule_number_is_in_the_summary():
    d = json.loads(json.dumps(TrackerSettings().to_dict()))
    for key in FLAT_NAMES:                      # the fields summary.json always had
        assert key in d
    for group in GROUPS:
        assert group in d
    start = d["start"]
    assert start["step_factor"] == 2.0 and start["extra_levels"] == 2
    assert start["max_iterations"] == 10 and start["shortlist"] == 6
    assert start["finalists"] == 3 and start["root_blocks"] == 2
    assert StartSettings(axial_shifts=[0, 0.1]).axial_shifts == (0.0, 0.1)


def test_the_summary_settings_build_the_same_settings_again():
    s = TrackerSettings(heading_frames=4, search=SearchSettings(passes=3))
    again = TrackerSettings(**json.loads(json.dumps(s.to_dict())))
    assert again == s


def test_a_preset_is_the_defaults_with_its_groups_changed():
    from depthtrack.track.settings import PRESETS, preset

    assert preset("default") == TrackerSettings()
    fast = preset("fast")
    assert fast.shape.enabled is False and fast.search.passes == 1 and fast.polish.fine_tile == 0
    assert fast.heading.every == 8 and fast.heading.limb_every == 8 and fast.propose.reach_every == 4
    # the default takes a fresh look every 8th frame; the fast preset none (as measured)
    assert TrackerSettings().judge.look_every == 8 and fast.judge.look_every == 0
    assert TrackerSettings().heading.reseat_free == 0.5 and fast.heading.reseat_free == 0.0
    assert TrackerSettings().heading.reseat_hidden == 0.01 and fast.heading.reseat_hidden == 0.0
    # everything the preset does not name stays at its default
    assert fast.heading.frames == HeadingSettings().frames and fast.search.levels == SearchSettings().levels
    assert set(PRESETS) == {"default", "fast"}
    with pytest.raises(InputError, match="unknown preset"):
        preset("fastest")


def test_settings_laid_over_a_preset_change_only_the_fields_they_name():
    from types import SimpleNamespace

    from depthtrack.cli.track import tracker_settings

    s = tracker_settings(SimpleNamespace(preset="fast", settings='{"heading": {"every": 4}}'))
    assert s.heading.every == 4 and s.heading.limb_every == 8 and s.shape.enabled is False
    # without a preset, --settings builds on the defaults, as it always did
    plain = tracker_settings(SimpleNamespace(settings='{"heading": {"every": 4}}'))
    assert plain == TrackerSettings(heading=HeadingSettings(every=4))
    # a whole summary.json's settings rebuild that track's settings, whatever the preset
    summary = json.dumps({"settings": tracker_settings(SimpleNamespace(preset="fast")).to_dict()})
    assert tracker_settings(SimpleNamespace(settings=summary)) == tracker_settings(SimpleNamespace(preset="fast"))
    # --shape-fit still has the last word
    assert tracker_settings(SimpleNamespace(preset="fast", shape_fit="on")).shape.enabled is True


def test_the_shape_trial_without_rechecks_keeps_the_start_check():
    from depthtrack.track.height import NO_RECHECKS

    s = TrackerSettings().updated(NO_RECHECKS)
    assert (s.heading.every, s.heading.limb_every, s.heading.search_every) == (0, 0, 0)
    assert s.propose.reach_every == 0
    assert s.heading.frames == TrackerSettings().heading.frames > 0     # the start's check stays

