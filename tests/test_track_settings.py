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
