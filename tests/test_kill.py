"""Outputs survive kills and replacements: ``kill -9`` during ``synth`` and ``track``, the
rename order of :func:`depthtrack.io.atomic.atomic_path`, stale temporaries, the marker
file and ``--force``."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from depthtrack.cli import main
from depthtrack.io.atomic import TMP_TAG, _host, atomic_path, clean_stale
from depthtrack.io.outputs import MARKER, check_output, read_marker
from depthtrack.io.sequence import open_sequence

REPO = Path(__file__).resolve().parents[1]


def temporaries(path: Path):
    return sorted(p for p in path.parent.iterdir() if p.name.startswith(f".{path.name}.{TMP_TAG}."))


def dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def stale_temporary(path: Path, pid: int) -> Path:
    tmp = path.parent / f".{path.name}.{TMP_TAG}.{_host()}.{pid}.abc123"
    tmp.mkdir()
    return tmp


def cli(*argv, timeout=300):
    # this checkout first, and whatever else the user's PYTHONPATH holds after it
    path = os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")]))
    env = dict(os.environ, PYTHONPATH=path)
    return subprocess.Popen([sys.executable, "-m", "depthtrack", *map(str, argv)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def kill_when(proc, ready, limit=120.0):
    """``kill -9`` the process as soon as ``ready()`` holds; fails if it ends first."""
    t0 = time.monotonic()
    while not ready():
        assert proc.poll() is None, f"ended before the kill: {proc.communicate()}"
        assert time.monotonic() - t0 < limit, "never got ready"
        time.sleep(0.02)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()


# ------------------------------------------------------------------ atomic replacement
def test_replacing_a_directory_keeps_one_complete_version(tmp_path):
    out = tmp_path / "out"
    with atomic_path(out) as tmp:
        tmp.mkdir()
        (tmp / "a.txt").write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_path(out) as tmp:
            tmp.mkdir()
            (tmp / "a.txt").write_text("half")
            raise RuntimeError("killed while writing")
    assert (out / "a.txt").read_text() == "old" and not temporaries(out)
    with atomic_path(out) as tmp:
        tmp.mkdir()
        (tmp / "b.txt").write_text("new")
    assert sorted(os.listdir(out)) == ["b.txt"] and not temporaries(out)


def test_a_kill_between_the_renames_is_undone_by_the_next_run(tmp_path):
    """The old output waits inside the dead writer's temporary: the next run moves it back."""
    out = tmp_path / "out"
    tmp = stale_temporary(out, dead_pid())
    (tmp / ".old").mkdir()
    (tmp / ".old" / "a.txt").write_text("old")
    (tmp / "out").mkdir()                                    # the new one, never renamed in
    assert clean_stale(out) == [tmp]
    assert (out / "a.txt").read_text() == "old" and not temporaries(out)


def test_temporaries_of_live_writers_are_left_alone(tmp_path):
    out = tmp_path / "out"
    live = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        mine = stale_temporary(out, live.pid)
        dead = stale_temporary(out, dead_pid())
        other_host = out.parent / f".out.{TMP_TAG}.elsewhere.{dead_pid()}.x"
        other_host.mkdir()
        assert clean_stale(out) == [dead]
        assert mine.is_dir() and other_host.is_dir() and not dead.exists()
    finally:
        live.kill()
        live.wait()


def test_marker_lets_a_command_replace_its_own_output_only(tmp_path, capsys):
    out = tmp_path / "rep"
    check_output(out, command="eval")
    with atomic_path(out) as tmp:
        tmp.mkdir()
        (tmp / "metrics.json").write_text("{}")
    assert read_marker(out)["command"] == "eval"
    check_output(out, command="eval")                       # its own: fine
    with pytest.raises(Exception, match="output of `depthtrack eval`"):
        check_output(out, command="track")
    check_output(out, command="track", force=True)          # --force: fine


def test_eval_report_replaces_its_own_report_and_refuses_a_foreign_directory(tmp_path, capsys):
    from depthtrack.body import BodyModel
    from depthtrack.camera import Camera
    from depthtrack.io.sequence import write_sequence
    from depthtrack.io.track_output import write_track

    body = BodyModel.default(height=1.75)
    poses = np.tile(body.default_pose((0.0, 0.0, 3.0)), (3, 1))
    joints = body.joint_positions(poses)
    camera = Camera(width=32, height=24, fx=30.0, fy=30.0, cx=16.0, cy=12.0)
    seq = write_sequence(tmp_path / "seq", np.zeros((3, 24, 32)), camera, 25.0, joints=joints)
    track = write_track(tmp_path / "track", joints, poses, body.pose_names, body, 25.0, {"method": "hc"})
    report = tmp_path / "report"
    argv = ["eval", str(seq), "--track", str(track), "--report", str(report), "--json", "--quiet"]
    assert main(argv) == 0 and main(argv) == 0              # the second run replaces the first
    assert read_marker(report)["command"] == "eval" and (report / "metrics.json").is_file()
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("keep me")
    capsys.readouterr()
    assert main(argv[:-3] + [str(foreign), "--json", "--quiet"]) == 2
    assert "--force" in capsys.readouterr().err and (foreign / "notes.txt").read_text() == "keep me"
    assert main(argv[:-3] + [str(foreign), "--json", "--quiet", "--force"]) == 0
    assert not (foreign / "notes.txt").exists() and (foreign / MARKER).is_file()
    assert not temporaries(report) and not temporaries(foreign)


# ------------------------------------------------------------------ kill -9
def test_kill_during_synth_leaves_the_old_output_and_the_next_run_cleans_up(tmp_path):
    out = tmp_path / "seq"
    first = cli("synth", "--procedural", "wave", out, "--seconds", "0.2", "--noise", "none", "--quiet")
    assert first.wait() == 0, first.communicate()
    old = len(open_sequence(out))

    proc = cli("synth", "--procedural", "wave", out, "--seconds", "60", "--quiet")

    def writing():                                           # frames are going into the temporary
        return any((t / "seq" / "depth").is_dir() and any((t / "seq" / "depth").iterdir())
                   for t in temporaries(out))
    kill_when(proc, writing)
    assert temporaries(out)                                  # what the kill left...
    assert len(open_sequence(out)) == old                    # ...and the old output, complete

    again = cli("synth", "--procedural", "wave", out, "--seconds", "0.12", "--noise", "none", "--quiet")
    assert again.wait() == 0, again.communicate()
    assert len(open_sequence(out)) == 3 and not temporaries(out)
    assert read_marker(out)["command"] == "synth"


def test_kill_during_track_leaves_no_output_and_the_next_run_succeeds(tmp_path):
    seq = tmp_path / "seq"
    made = cli("synth", "--procedural", "wave", seq, "--seconds", "0.24", "--quiet")
    assert made.wait() == 0, made.communicate()
    out = tmp_path / "track"
    proc = cli("track", seq, "-o", out, "--method", "hc", "--quiet")

    def tracking():                                          # GL is up: the tracker is at work
        try:
            return "libEGL" in Path(f"/proc/{proc.pid}/maps").read_text()
        except OSError:
            return False
    kill_when(proc, tracking)
    assert proc.returncode == -signal.SIGKILL
    assert not out.exists() and not temporaries(out)
    stale = stale_temporary(out, dead_pid())                  # as a kill while writing leaves it
    (stale / "track").mkdir()
    again = cli("track", seq, "-o", out, "--method", "hc", "--quiet")
    assert again.wait() == 0, again.communicate()
    assert not stale.exists() and not temporaries(out)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == 6 and read_marker(out)["command"] == "track"


def test_a_failed_overlay_leaves_the_track_complete_and_unnamed(tmp_path, monkeypatch):
    """Overlay after the track: on failure the track stays whole and its summary names no overlay."""
    import errno

    from depthtrack.body import BodyModel
    from depthtrack.cli import track as track_cli
    from depthtrack.errors import InputError
    from depthtrack.evaluate import overlay as overlay_module
    from depthtrack.io.track_output import read_track, write_track

    body = BodyModel.default(height=1.75)
    poses = np.tile(body.default_pose((0.0, 0.0, 3.0)), (3, 1))
    out = write_track(tmp_path / "track", body.joint_positions(poses), poses, body.pose_names, body, 25.0,
                      {"method": "hc"})

    def full_disk(path, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", str(path))
    monkeypatch.setattr(overlay_module, "write_overlay", full_disk)
    with pytest.raises(InputError, match="no space left on device.*track in .* is complete"):
        track_cli._add_overlay(out, tmp_path / "v.mp4", None, poses, body, {})
    assert "overlay" not in read_track(out).summary and not (tmp_path / "v.mp4").exists()

    monkeypatch.setattr(overlay_module, "write_overlay", lambda path, *a, **k: Path(path))
    track_cli._add_overlay(out, tmp_path / "v.mp4", None, poses, body, {})
    assert read_track(out).summary["overlay"] == str(tmp_path / "v.mp4")
