"""A generated corpus of bad inputs and output places, each refused the same way.

Every case (built in ``tests/bad_input_corpus.py``) runs the CLI in-process
(``depthtrack.cli.main``) and must end with exit status 2, one line on stderr naming the
file at fault, no traceback, and nothing left in the output place (not created, or
unchanged, and no temporaries beside it). A few cases run as real subprocesses to check
the same from the outside. glTF and C3D have no command; their loaders must raise one
:class:`InputError` naming the file.
"""
import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from bad_input_corpus import CASES, REPO, copy_tree, make_base
from depthtrack.cli import main
from depthtrack.errors import InputError


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    """A valid tiny sequence with ground truth, a track of it, a BVH and markings."""
    return make_base(tmp_path_factory.mktemp("bad_inputs"))


def snapshot(path: Path):
    """What is at ``path`` (recursively: names and content hashes), and its temporaries."""
    def tree(p):
        if p.is_symlink() or p.is_file():
            return hashlib.sha1(p.read_bytes()).hexdigest()
        if p.is_dir():
            return {c.name: tree(c) for c in sorted(p.iterdir())}
        return None
    siblings = sorted(n for n in os.listdir(path.parent) if ".depthtrack-tmp." in n) \
        if path.parent.is_dir() else []
    return tree(path), siblings


def run_cli(capsys, argv):
    code = main(argv)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.mark.parametrize("name", sorted(CASES))
def test_bad_input_refused_in_one_line(base, capfd, name):
    argv, expect, out = CASES[name](base)
    before = snapshot(out)
    capfd.readouterr()
    code = main(argv)
    captured = capfd.readouterr()
    err = captured.err.strip()
    assert code == 2, (code, err)
    assert len(err.splitlines()) == 1, err                # one line, nothing else (libpng included)
    assert "Traceback" not in err
    assert err.startswith("depthtrack"), err
    assert expect in err, err
    assert snapshot(out) == before                      # nothing created, changed or left beside it


def test_the_corpus_is_large():
    assert len(CASES) >= 100


def test_gltf_loader_refuses_in_one_line(tmp_path, recwarn):
    from depthtrack.body.gltf import load_skinned_gltf

    bad = {"empty.glb": b"", "garbage.glb": b"glTF" + bytes(range(200)), "text.gltf": b"{not json",
           "list.gltf": b"[]", "noskin.gltf": json.dumps({"asset": {"version": "2.0"},
                                                           "nodes": [{"name": "a"}]}).encode(),
           "badbuffer.gltf": json.dumps({"asset": {"version": "2.0"}, "nodes": [{"mesh": 0, "skin": 0}],
                                         "skins": [{"joints": [0], "inverseBindMatrices": 0}],
                                         "meshes": [{"primitives": [{"attributes": {"POSITION": 5}}]}],
                                         "accessors": [], "buffers": [{"uri": "missing.bin",
                                                                        "byteLength": 64}]}).encode()}
    for name, data in bad.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(InputError) as info:
            load_skinned_gltf(tmp_path / name)
        assert name in str(info.value) and "\n" not in str(info.value)
    assert not recwarn.list                                 # no warnings on stderr either


def test_c3d_reader_refuses_in_one_line(tmp_path, capfd):
    from depthtrack.io.c3d import read_c3d_markers

    import ezc3d

    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = [100.0]
    c3d["parameters"]["POINT"]["LABELS"]["value"] = ("LFHD", "RFHD")
    c3d["data"]["points"] = np.ones((4, 2, 50))
    c3d.write(str(tmp_path / "good.c3d"))
    good = (tmp_path / "good.c3d").read_bytes()
    for name, data in {"empty.c3d": b"", "garbage.c3d": bytes(range(256)) * 3,
                       "short.c3d": b"\x02\x50" + b"\x00" * 100, "half.c3d": good[:len(good) // 2],
                       "header.c3d": good[:512], "zero-blocks.c3d": good[:2] + b"\x00" * (len(good) - 2),
                       "no-points.c3d": good[:512 + 30] + b"\xff" * (len(good) - 542)}.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(InputError) as info:
            read_c3d_markers(tmp_path / name)
        assert name in str(info.value) and "\n" not in str(info.value)
        assert capfd.readouterr().err == ""                 # ezc3d says nothing on stderr


@pytest.mark.parametrize("argv_key", ["png", "meta", "arg", "out"])
def test_real_processes_refuse_in_one_line(base, argv_key):
    """The same through ``python -m depthtrack``: exit status 2, one line, nothing written."""
    name = {"png": "png-truncated40", "meta": "meta-camera-fx-1e+300", "arg": "arg-synth--seed=-1",
            "out": "out-report-is-seq"}[argv_key]
    argv, expect, out = CASES[name](_fresh(base, argv_key))
    before = snapshot(out)
    # the repository first, the caller's own path after it (packages installed outside the venv)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])))
    proc = subprocess.run([sys.executable, "-m", "depthtrack", *argv], capture_output=True, text=True, env=env,
                          timeout=120)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and expect in lines[0], proc.stderr
    assert snapshot(out) == before


def _fresh(base, key):
    """A second copy of the good inputs, so these cases do not collide with the in-process ones."""
    root = base.parent / f"{base.name}-proc-{key}"
    if not root.exists():
        copy_tree(base, root)
        import shutil
        shutil.rmtree(root / "cases", ignore_errors=True)
    return root


def test_read_only_output_place_is_refused_before_work(tmp_path, capsys):
    """A directory we may not write in (root may write anywhere: then there is nothing to test)."""
    if os.geteuid() == 0:
        pytest.skip("running as root, which writes into read-only directories; the same refusal is "
                    "covered by the output-under-a-file cases")
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        assert main(["synth", "--procedural", "wave", str(locked / "seq")]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "locked" in err and "cannot write" in err
        assert os.listdir(locked) == []
    finally:
        locked.chmod(0o700)
