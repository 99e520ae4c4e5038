"""``depthtrack eval`` batches: a spawned process pool and Dask give the serial run's figures;
a sequence that cannot be read is reported and the others still complete."""
import json

import pytest

from depthtrack.cli import main
from depthtrack.evaluate.runs import evaluate
from depthtrack.synth.generate import synthesize_procedural

METHODS = ["ep"]     # the quickest method: the wiring is under test, not the tracker


def _figures(data: dict) -> dict:
    """The JSON without ``fps`` and ``wall_fps`` (timings, the only things allowed to differ)."""
    if isinstance(data, dict):
        return {k: _figures(v) for k, v in data.items() if k not in ("fps", "wall_fps")}
    return data


@pytest.fixture(scope="module")
def seqs(tmp_path_factory):
    root = tmp_path_factory.mktemp("batch")
    a = root / "wave"
    b = root / "squat"
    synthesize_procedural("wave", a, seconds=0.16, height=1.7)       # 4 frames each
    synthesize_procedural("squat", b, seconds=0.16, height=1.8)
    broken = root / "broken"
    broken.mkdir()
    (broken / "sequence.json").write_text('{"format": "depthtrack-sequence/1", "fps": ')
    serial = evaluate([a, b], methods=METHODS).to_dict()
    return {"a": a, "b": b, "broken": broken, "serial": serial, "root": root}


def test_workers_match_serial_and_a_broken_sequence_is_reported(seqs, tmp_path, capsys):
    tracks = tmp_path / "tracks"
    code = main(["eval", str(seqs["a"]), str(seqs["broken"]), str(seqs["b"]), "--methods", "ep",
                 "--workers", "2", "--json", "--quiet", "--tracks-out", str(tracks)])
    out = capsys.readouterr()
    assert code == 2                                    # bad input, reported after the rest ran
    data = json.loads(out.out)
    assert set(data["failed"]) == {"broken"} and "sequence.json" in data["failed"]["broken"]
    del data["failed"]
    assert _figures(data) == _figures(seqs["serial"])
    assert list(data["sequences"]) == ["wave", "squat"]  # the given order, whatever finished first
    err = out.err.strip().splitlines()
    assert err == [f"depthtrack eval: {seqs['broken'] / 'sequence.json'}: invalid JSON "
                   "(line 1: Expecting value)"]
    for name in ("wave", "squat"):                       # each task wrote its own track
        assert sorted(p.name for p in (tracks / name / "ep").iterdir()) == [
            "body.json", "joints.csv", "poses.npz", "summary.json", "track.bvh"]
    assert not [p for p in tracks.rglob(".*")]          # no temporaries left
    # the spawned workers computed with this process's OpenBLAS kernels (pinned alike: README,
    # "The same figures on another machine")
    from depthtrack.environment import blas_kernels
    here = {lib["architecture"] for lib in blas_kernels()["libraries"]}
    for name in ("wave", "squat"):
        blas = json.loads((tracks / name / "ep" / "summary.json").read_text())["blas"]
        assert blas["libraries"] and {lib["architecture"] for lib in blas["libraries"]} <= here


def test_dask_local_cluster_matches_serial(seqs):
    pytest.importorskip("distributed")
    result = evaluate([seqs["a"], seqs["b"]], methods=METHODS, executor="dask", dask_address="local",
                      workers=2)
    assert not result.failures
    assert _figures(result.to_dict()) == _figures(seqs["serial"])


def test_unreachable_scheduler_is_one_line_exit_2(seqs, capsys, monkeypatch):
    pytest.importorskip("distributed")
    from depthtrack.evaluate import batch
    monkeypatch.setattr(batch, "DASK_CONNECT_TIMEOUT", "1s")       # nothing listens on port 9
    code = main(["eval", str(seqs["a"]), "--methods", "ep", "--dask", "tcp://127.0.0.1:9", "--quiet"])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Dask scheduler" in err[0]


def test_library_call_raises_on_a_broken_sequence_by_default(seqs):
    from depthtrack.errors import InputError

    with pytest.raises(InputError, match="sequence.json"):
        evaluate([seqs["broken"]], methods=METHODS)
    kept = evaluate([seqs["broken"]], methods=METHODS, keep_going=True)
    assert kept.results == [] and [f.name for f in kept.failures] == ["broken"]
