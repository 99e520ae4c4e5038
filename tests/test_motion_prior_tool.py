"""tools/make_motion_prior.py fits on the train clips of the motion split by default."""
import json
from pathlib import Path
from tool_module import load_tool

REPO = Path(__file__).resolve().parents[1]


def _tool():
    return load_tool("make_motion_prior")


def test_default_inputs_are_the_train_clips_only(tmp_path):
    split = json.loads((REPO / "depthtrack" / "data" / "motion_split.json").read_text())
    clips = _tool().train_clips(tmp_path)
    assert [str(p.relative_to(tmp_path)) for p in clips] == split["train"]
    held_out = set(split["dev"]) | set(split["test"])
    assert held_out and not held_out & set(split["train"])


def test_missing_train_clips_are_refused(tmp_path, capsys):
    assert _tool().main(["--data", str(tmp_path), "-o", str(tmp_path / "prior.json")]) == 2
    assert "train clips not found" in capsys.readouterr().err
    assert not (tmp_path / "prior.json").exists()
