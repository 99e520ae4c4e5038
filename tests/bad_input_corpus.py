"""The generated corpus of bad inputs and output places for ``tests/test_bad_inputs.py``.

Every case runs the CLI in-process (``depthtrack.cli.main``) and must end with exit
status 2, one line on stderr naming the file at fault, no traceback, and nothing left
in the output place (not created, or unchanged, and no temporaries beside it). A few
cases run as real subprocesses to check the same from the outside. glTF and C3D have no
command; their loaders must raise one :class:`InputError` naming the file.
"""
import json
import os
import struct
import zlib
from pathlib import Path

import cv2
import numpy as np

from depthtrack.body import BodyModel
from depthtrack.camera import Camera
from depthtrack.io.bvh import write_bvh
from depthtrack.io.sequence import write_sequence
from depthtrack.io.track_output import write_track

REPO = Path(__file__).resolve().parents[1]
FRAMES = 3
CAMERA = Camera(width=32, height=24, fx=30.0, fy=30.0, cx=16.0, cy=12.0)


# ------------------------------------------------------------------ the good inputs
def make_base(root):
    """A valid tiny sequence with ground truth, a track of it, a BVH and markings."""
    body = BodyModel.default(height=1.75)
    poses = np.tile(body.default_pose((0.0, 0.0, 3.0)), (FRAMES, 1))
    joints = body.joint_positions(poses)
    depth = np.full((FRAMES, CAMERA.height, CAMERA.width), 3.0, np.float32)
    write_sequence(root / "seq", depth, CAMERA, 25.0, joints=joints, subject=1.75)
    write_track(root / "track", joints, poses, body.pose_names, body, 25.0, {"method": "hc"})
    write_bvh(root / "motion.bvh", body, np.tile(body.default_pose((0.0, 0.0, 0.0)), (4, 1)), 25.0)
    (root / "markings.csv").write_text("frame,joint,u,v,view,nearer\n0,hips,10,10,side,\n")
    (root / "lengths.json").write_text(json.dumps([0.3] * 13))
    (root / "afile").write_text("not a directory\n")
    return root


def copy_tree(src: Path, dst: Path) -> Path:
    import shutil
    shutil.copytree(src, dst)
    return dst


def png16(image) -> bytes:
    ok, data = cv2.imencode(".png", np.ascontiguousarray(image))
    assert ok
    return data.tobytes()


def frame_bytes():
    return png16(np.full((CAMERA.height, CAMERA.width), 3000, np.uint16))


def corrupt_idat(data: bytes) -> bytes:
    at = data.index(b"IDAT") + 6
    return data[:at] + bytes([data[at] ^ 0xFF]) + data[at + 1:]


def rechunk(data: bytes) -> bytes:
    """Flip an IDAT byte and fix the CRC: structurally sound, undecodable data."""
    at = data.index(b"IDAT")
    length = struct.unpack(">I", data[at - 4:at])[0]
    body = bytearray(data[at:at + 4 + length])
    body[6:] = b"\xff" * (len(body) - 6)
    crc = struct.pack(">I", zlib.crc32(bytes(body)))
    return data[:at] + bytes(body) + crc + data[at + 8 + length:]


# ------------------------------------------------------------------ the corpus
CASES = {}


def case(name):
    def register(fn):
        CASES[name] = fn
        return fn
    return register


def seq_with(root, name, edit):
    """A copy of the good sequence with ``edit(seq_dir)`` applied; returns the copy."""
    seq = copy_tree(root / "seq", root / "cases" / name / "seq")
    edit(seq)
    return seq


def track_argv(root, name, seq):
    out = root / "cases" / name / "out"
    return ["track", str(seq), "-o", str(out), "--quiet"], out


def eval_argv(root, name, seq, track=None):
    out = root / "cases" / name / "report"
    return ["eval", str(seq), "--track", str(track or root / "track"), "--report", str(out),
            "--quiet", "--json"], out


# PNG frames (frame 0; headers are checked on opening, pixels on reading)
def _png_case(name, make):
    @case(f"png-{name}")
    def build(root, _name=f"png-{name}"):
        def edit(seq):
            (seq / "depth" / "000000.png").write_bytes(make())
        seq = seq_with(root, _name, edit)
        argv, out = track_argv(root, _name, seq)
        return argv, "000000.png", out


_GOOD = None


def good():
    global _GOOD
    if _GOOD is None:
        _GOOD = frame_bytes()
    return _GOOD


for _cut in (0, 5, 8, 20, 33, 40, 60, -30, -12, -1):
    _png_case(f"truncated{_cut}", lambda c=_cut: good()[:c] if c else b"")
_png_case("8bit", lambda: png16(np.full((24, 32), 30, np.uint8)))
_png_case("rgb8", lambda: png16(np.full((24, 32, 3), 30, np.uint8)))
_png_case("rgb16", lambda: png16(np.full((24, 32, 3), 3000, np.uint16)))
_png_case("rgba16", lambda: png16(np.full((24, 32, 4), 3000, np.uint16)))
_png_case("wide", lambda: png16(np.full((24, 33), 3000, np.uint16)))
_png_case("tall", lambda: png16(np.full((25, 32), 3000, np.uint16)))
_png_case("tiny", lambda: png16(np.full((1, 1), 3000, np.uint16)))
_png_case("jpeg", lambda: cv2.imencode(".jpg", np.full((24, 32), 30, np.uint8))[1].tobytes())
_png_case("text", lambda: b"hello, I am not a picture\n" * 3)
_png_case("random", lambda: np.random.default_rng(1).integers(0, 256, 500, dtype=np.uint8).tobytes())
_png_case("badcrc", lambda: corrupt_idat(good()))
_png_case("baddata", lambda: rechunk(good()))
_png_case("noiend", lambda: good()[:-12])


# frame files
def _frames_case(name, edit, expect):
    @case(f"frames-{name}")
    def build(root, _name=f"frames-{name}"):
        seq = seq_with(root, _name, edit)
        argv, out = track_argv(root, _name, seq)
        return argv, expect, out


def _rm(*names):
    def edit(seq):
        for n in names:
            os.remove(seq / "depth" / n)
    return edit


def _rename(a, b):
    return lambda seq: os.rename(seq / "depth" / a, seq / "depth" / b)


_frames_case("gap", _rm("000001.png"), "depth")
_frames_case("nofirst", _rm("000000.png"), "depth")
_frames_case("none", _rm("000000.png", "000001.png", "000002.png"), "depth")
_frames_case("nodir", lambda seq: __import__("shutil").rmtree(seq / "depth"), "depth")
_frames_case("badname", _rename("000002.png", "frame2.png"), "frame2.png")
_frames_case("twice", lambda seq: (seq / "depth" / "1.png").write_bytes(good()), ".png")
_frames_case("renumbered", _rename("000002.png", "000009.png"), "depth")
_frames_case("dirframe", lambda seq: (os.remove(seq / "depth" / "000001.png"),
                                      os.mkdir(seq / "depth" / "000001.png")), "000001.png")


# sequence.json
def _meta_case(name, edit, raw=None):
    @case(f"meta-{name}")
    def build(root, _name=f"meta-{name}"):
        def apply(seq):
            path = seq / "sequence.json"
            if raw is not None:
                path.write_bytes(raw)
                return
            meta = json.loads(path.read_text())
            edit(meta)
            path.write_text(json.dumps(meta))
        seq = seq_with(root, _name, apply)
        argv, out = track_argv(root, _name, seq)
        return argv, "sequence.json", out


def _set(*keys_value):
    *keys, value = keys_value

    def edit(meta):
        d = meta
        for k in keys[:-1]:
            d = d[k]
        d[keys[-1]] = value
    return edit


def _del(*keys):
    def edit(meta):
        d = meta
        for k in keys[:-1]:
            d = d[k]
        del d[keys[-1]]
    return edit


_meta_case("empty", None, raw=b"")
_meta_case("notjson", None, raw=b"{fps: 25")
_meta_case("binary", None, raw=bytes(range(256)))
_meta_case("array", None, raw=b"[1, 2, 3]")
for _k in ("format", "fps", "depth_scale", "camera"):
    _meta_case(f"no-{_k}", _del(_k))
for _k in ("width", "height", "fx", "fy", "cx", "cy"):
    _meta_case(f"no-camera-{_k}", _del("camera", _k))
for _k, _v in [("fx", float("nan")), ("fx", float("inf")), ("fx", 0), ("fx", -220.0), ("fx", 1e300),
               ("fy", 0.0), ("fy", -1), ("fy", "220"), ("cx", float("nan")), ("cx", 1e9), ("cy", -1e6),
               ("width", 32.5), ("width", 0), ("width", -32), ("width", "32"), ("width", 10 ** 9),
               ("height", 1e12), ("height", None), ("width", True)]:
    _meta_case(f"camera-{_k}-{_v}", _set("camera", _k, _v))
for _k, _v in [("fps", 0), ("fps", -25), ("fps", float("nan")), ("fps", 1e9), ("fps", "fast"),
               ("depth_scale", 0), ("depth_scale", -0.001), ("depth_scale", 5.0),
               ("format", "depthtrack-sequence/99"), ("camera", [1, 2]), ("subject", [1.75])]:
    _meta_case(f"{_k}-{_v}", _set(_k, _v))
for _v in (1000, 0, -1.75, "tall", float("nan"), 0.1):
    _meta_case(f"height-{_v}", _set("subject", "height_m", _v))


# ground-truth CSVs (scored with eval --track)
def _gt_case(name, text, file="joints.csv"):
    @case(f"gt-{file[:-4]}-{name}")
    def build(root, _name=f"gt-{file[:-4]}-{name}"):
        def edit(seq):
            data = text(seq / "groundtruth" / "joints.csv") if callable(text) else text
            (seq / "groundtruth" / file).write_bytes(data if isinstance(data, bytes) else data.encode())
        seq = seq_with(root, _name, edit)
        argv, out = eval_argv(root, _name, seq)
        return argv, file, out


def _edit_line(index, fn):
    def text(path):
        lines = path.read_text().splitlines()
        lines[index] = fn(lines[index])
        return "\n".join(lines) + "\n"
    return text


def _field(k, value):
    return _edit_line(3, lambda line: ",".join(value if i == k else f for i, f in enumerate(line.split(","))))


_gt_case("nan", _field(2, "nan"))
_gt_case("inf", _field(3, "inf"))
_gt_case("text", _field(4, "abc"))
_gt_case("empty-number", _field(2, ""))
_gt_case("unknown-joint", _field(1, "tail"))
_gt_case("negative-frame", _field(0, "-1"))
_gt_case("fraction-frame", _field(0, "1.5"))
_gt_case("beyond", _field(0, "99"))
_gt_case("four-fields", _edit_line(3, lambda line: line.rsplit(",", 1)[0]))
_gt_case("duplicate", lambda p: p.read_text() + p.read_text().splitlines()[1] + "\n")
_gt_case("header", _edit_line(0, lambda line: "frame,name,x,y,z"))
_gt_case("no-header", lambda p: "\n".join(p.read_text().splitlines()[1:]) + "\n")
_gt_case("empty", "")
_gt_case("header-only", "frame,joint,x,y,z\n")
_gt_case("binary", bytes(range(256)) * 4)
_gt_case("cut-short", lambda p: "\n".join(l for l in p.read_text().splitlines() if not l.startswith("2,")) + "\n")
_gt_case("nan", "frame,marker,x,y,z\n0,LFHD,nan,0,0\n", file="markers.csv")
_gt_case("text", "frame,marker,x,y,z\n0,LFHD,a,b,c\n", file="markers.csv")
_gt_case("binary", b"\x00\x01\x02\xff" * 50, file="markers.csv")


# .npz sequences
def _npz_case(name, arrays, raw=None):
    @case(f"npz-{name}")
    def build(root, _name=f"npz-{name}"):
        path = root / "cases" / _name / "seq.npz"
        path.parent.mkdir(parents=True)
        if raw is not None:
            path.write_bytes(raw)
        else:
            meta = json.dumps({"format": "depthtrack-sequence/1", "fps": 25.0, "depth_scale": 0.001,
                               "camera": CAMERA.to_dict(), "subject": {"height_m": 1.75}})
            good_arrays = {"meta": np.array(meta), "depth": np.full((FRAMES, 24, 32), 3000, np.uint16),
                           "joints": np.zeros((FRAMES, 15, 3))}
            np.savez(path, **arrays(good_arrays))
        argv, out = eval_argv(root, _name, path)
        return argv, "seq.npz", out


_npz_case("joints-strings", lambda a: {**a, "joints": np.full((FRAMES, 15, 3), "1.0")})
_npz_case("joints-shape", lambda a: {**a, "joints": np.zeros((FRAMES, 14, 3))})
_npz_case("joints-inf", lambda a: {**a, "joints": np.full((FRAMES, 15, 3), np.inf)})
_npz_case("joints-short", lambda a: {**a, "joints": np.concatenate([np.zeros((2, 15, 3)),
                                                                     np.full((1, 15, 3), np.nan)])})
_npz_case("depth-float", lambda a: {**a, "depth": a["depth"].astype(np.float32)})
_npz_case("depth-2d", lambda a: {**a, "depth": a["depth"][0]})
_npz_case("depth-empty", lambda a: {**a, "depth": a["depth"][:0], "joints": a["joints"][:0]})
_npz_case("depth-size", lambda a: {**a, "depth": a["depth"][:, :20]})
_npz_case("no-meta", lambda a: {k: v for k, v in a.items() if k != "meta"})
_npz_case("meta-json", lambda a: {**a, "meta": np.array("{oops")})
_npz_case("not-zip", None, raw=b"PK\x03\x04 this is no zip file")
_npz_case("empty-file", None, raw=b"")


# track outputs (eval --track)
def _track_case(name, file, data):
    @case(f"track-{name}")
    def build(root, _name=f"track-{name}"):
        track = copy_tree(root / "track", root / "cases" / _name / "track")
        if data is None:
            os.remove(track / file)
        else:
            (track / file).write_bytes(data if isinstance(data, bytes) else data.encode())
        argv, out = eval_argv(root, _name, root / "seq", track)
        return argv, file, out


_track_case("summary-list", "summary.json", "[]")
_track_case("summary-text", "summary.json", '"hc"')
_track_case("summary-invalid", "summary.json", "{method")
_track_case("summary-binary", "summary.json", bytes(range(256)))
_track_case("summary-missing", "summary.json", None)
_track_case("poses-missing", "poses.npz", None)
_track_case("poses-garbage", "poses.npz", b"garbage")
_track_case("joints-text", "joints.csv", "frame,joint,x,y,z\n0,head,a,b,c\n")
_track_case("joints-missing", "joints.csv", None)


# BVH motions (synth)
def _bvh_case(name, make):
    @case(f"bvh-{name}")
    def build(root, _name=f"bvh-{name}"):
        path = root / "cases" / _name / "motion.bvh"
        path.parent.mkdir(parents=True)
        text = (root / "motion.bvh").read_text()
        data = make(text)
        path.write_bytes(data if isinstance(data, bytes) else data.encode())
        out = root / "cases" / _name / "synth"
        return ["synth", str(path), str(out), "--seconds", "0.1", "--noise", "none", "--quiet"], \
            "motion.bvh", out


def _motion_lines(text):
    head, motion = text.split("MOTION\n")
    return head, motion.splitlines()


_bvh_case("empty", lambda t: "")
_bvh_case("binary", lambda t: bytes(range(256)) * 8)
_bvh_case("truncated-hierarchy", lambda t: t[:len(t.split("MOTION")[0]) // 2])
_bvh_case("no-motion", lambda t: t.split("MOTION")[0])
_bvh_case("nan", lambda t: t.replace("MOTION\n", "MOTION\n").rsplit("\n", 2)[0] + "\n"
          + " ".join(["nan"] * len(t.rsplit("\n", 2)[1].split())) + "\n")
_bvh_case("text-number", lambda t: t.rsplit("\n", 2)[0] + "\n"
          + " ".join(["x"] * len(t.rsplit("\n", 2)[1].split())) + "\n")
_bvh_case("short-row", lambda t: t.rsplit("\n", 2)[0] + "\n1 2 3\n")
_bvh_case("frames-claimed", lambda t: t.replace("Frames: 4", "Frames: 40"))
_bvh_case("frame-time-zero", lambda t: t.replace("Frame Time: 0.04", "Frame Time: 0"))
_bvh_case("frame-time-negative", lambda t: t.replace("Frame Time: 0.04", "Frame Time: -0.04"))
_bvh_case("unbalanced", lambda t: t.replace("}", "", 1))


# markings and lengths (swim reconstruct)
def _markings_case(name, markings=None, lengths=None, expect="markings.csv"):
    @case(f"swim-{name}")
    def build(root, _name=f"swim-{name}"):
        d = root / "cases" / _name
        d.mkdir(parents=True)
        m, ln = d / "markings.csv", d / "lengths.json"
        m.write_bytes(markings if markings is not None else (root / "markings.csv").read_bytes())
        ln.write_bytes(lengths if lengths is not None else (root / "lengths.json").read_bytes())
        out = d / "joints.csv"
        return ["swim", "reconstruct", str(m), "--lengths", str(ln), "-o", str(out)], expect, out


_markings_case("markings-binary", markings=bytes(range(256)) * 4)
_markings_case("markings-empty", markings=b"")
_markings_case("markings-view", markings=b"frame,joint,u,v,view\n0,hips,1,2,front\n")
_markings_case("markings-text", markings=b"frame,joint,u,v,view\n0,hips,a,2,side\n")
_markings_case("markings-nan", markings=b"frame,joint,u,v,view\n0,hips,nan,2,side\n")
_markings_case("markings-frame", markings=b"frame,joint,u,v,view\n-3,hips,1,2,side\n")
_markings_case("lengths-text", lengths=b"[1, 2", expect="lengths.json")
_markings_case("lengths-negative", lengths=json.dumps([-0.3] * 13).encode(), expect="lengths.json")
_markings_case("lengths-nan", lengths=b"[" + b",".join([b"NaN"] * 13) + b"]", expect="lengths.json")
_markings_case("lengths-strings", lengths=json.dumps(["a"] * 13).encode(), expect="lengths.json")


# output places
def _out_case(name, build_argv):
    @case(f"out-{name}")
    def build(root, _name=f"out-{name}"):
        d = root / "cases" / _name
        d.mkdir(parents=True)
        return build_argv(root, d)


def _foreign_dir(d):
    f = d / "mine"
    f.mkdir()
    (f / "thesis.txt").write_text("my only copy\n")
    return f


_out_case("track-is-file", lambda r, d: (["track", str(r / "seq"), "-o", str(r / "afile")], "afile", r / "afile"))
_out_case("track-under-file", lambda r, d: (["track", str(r / "seq"), "-o", str(r / "afile" / "o")], "afile",
                                            r / "afile"))
_out_case("track-is-input", lambda r, d: (["track", str(r / "seq"), "-o", str(r / "seq")], "seq", r / "seq"))
_out_case("track-inside-input", lambda r, d: (["track", str(r / "seq"), "-o", str(r / "seq" / "t")], "seq",
                                              r / "seq"))
_out_case("track-holds-input", lambda r, d: (["track", str(r / "seq"), "-o", str(r)], str(r), r / "seq"))
_out_case("track-foreign", lambda r, d: (["track", str(r / "seq"), "-o", str(_foreign_dir(d))], "mine",
                                         d / "mine"))
_out_case("track-other-command", lambda r, d: (["track", str(r / "seq"), "-o", str(_marked(d, "eval"))],
                                               "marked", d / "marked"))
_out_case("overlay-in-out", lambda r, d: (["track", str(r / "seq"), "-o", str(d / "o"), "--overlay",
                                           str(d / "o" / "v.mp4")], "v.mp4", d / "o"))
_out_case("overlay-is-dir", lambda r, d: (["track", str(r / "seq"), "-o", str(d / "o"), "--overlay",
                                           str(_foreign_dir(d)) + ".mp4"] if os.rename(_foreign_dir(d), str(d / "mine") + ".mp4") is None else [],
                                          "mine.mp4", d / "o"))
_out_case("overlay-suffix", lambda r, d: (["track", str(r / "seq"), "-o", str(d / "o"), "--overlay",
                                           str(d / "v.avi")], "v.avi", d / "o"))
_out_case("report-is-seq", lambda r, d: (["eval", str(r / "seq"), "--track", str(r / "track"), "--report",
                                          str(r / "seq")], "seq", r / "seq"))
_out_case("report-is-track", lambda r, d: (["eval", str(r / "seq"), "--track", str(r / "track"), "--report",
                                            str(r / "track")], "track", r / "track"))
_out_case("report-in-track", lambda r, d: (["eval", str(r / "seq"), "--track", str(r / "track"), "--report",
                                            str(r / "track" / "rep")], "track", r / "track"))
_out_case("report-foreign", lambda r, d: (["eval", str(r / "seq"), "--track", str(r / "track"), "--report",
                                           str(_foreign_dir(d))], "mine", d / "mine"))
_out_case("report-under-file", lambda r, d: (["eval", str(r / "seq"), "--track", str(r / "track"), "--report",
                                              str(r / "afile" / "rep")], "afile", r / "afile"))
_out_case("synth-foreign", lambda r, d: (["synth", "--procedural", "wave", str(_foreign_dir(d))], "mine",
                                         d / "mine"))
_out_case("synth-is-file", lambda r, d: (["synth", "--procedural", "wave", str(r / "afile")], "afile",
                                         r / "afile"))
_out_case("synth-is-motion", lambda r, d: (["synth", str(r / "motion.bvh"), str(r / "motion.bvh")],
                                           "motion.bvh", r / "motion.bvh"))
_out_case("synth-npz-dir", lambda r, d: (["synth", "--procedural", "wave", str(_foreign_dir(d))
                                          .replace("mine", "x.npz") if os.mkdir(d / "x.npz") is None else ""],
                                         "x.npz", d / "x.npz"))
_out_case("synth-in-seq", lambda r, d: (["synth", "--procedural", "wave", str(r / "afile" / "seq")], "afile",
                                        r / "afile"))
_out_case("swim-eval-foreign", lambda r, d: (["swim", "evaluate", "--train", str(r / "motion.bvh"), "--test",
                                              str(r / "motion.bvh"), "--report", str(_foreign_dir(d))],
                                             "mine", d / "mine"))
_out_case("swim-eval-is-input", lambda r, d: (["swim", "evaluate", "--train", str(r / "motion.bvh"), "--test",
                                               str(r / "motion.bvh"), "--report", str(r / "motion.bvh")],
                                              "motion.bvh", r / "motion.bvh"))
_out_case("swim-deriv-foreign", lambda r, d: (["swim", "derivatives", str(r / "motion.bvh"), "--report",
                                               str(_foreign_dir(d))], "mine", d / "mine"))
_out_case("swim-train-dir", lambda r, d: (["swim", "train", str(r / "motion.bvh"), "-o", str(_foreign_dir(d))],
                                          "mine", d / "mine"))
_out_case("swim-train-input", lambda r, d: (["swim", "train", str(r / "motion.bvh"), "-o", str(r / "motion.bvh")],
                                            "motion.bvh", r / "motion.bvh"))
_out_case("reconstruct-input", lambda r, d: (["swim", "reconstruct", str(r / "markings.csv"), "--lengths",
                                              str(r / "lengths.json"), "-o", str(r / "markings.csv")],
                                             "markings.csv", r / "markings.csv"))
_out_case("name-too-long", lambda r, d: (["eval", str(r / "seq"), "--track", str(r / "track"), "--report",
                                          str(d / ("r" * 250))], "too long", d / ("r" * 250)))
_out_case("demo-foreign", lambda r, d: (["demo", "--out", str(_foreign_dir(d))], "mine", d / "mine"))
_out_case("demo-under-file", lambda r, d: (["demo", "--out", str(r / "afile" / "demo")], "afile", r / "afile"))


def _marked(d, command):
    from depthtrack.io.outputs import write_marker
    m = d / "marked"
    m.mkdir()
    write_marker(m, command)
    (m / "metrics.json").write_text("{}")
    return m


# numeric arguments
def _arg_case(name, argv, expect):
    @case(f"arg-{name}")
    def build(root, _name=f"arg-{name}"):
        out = root / "cases" / _name / "out"
        full = [a.replace("{seq}", str(root / "seq")).replace("{bvh}", str(root / "motion.bvh"))
                .replace("{out}", str(out)) for a in argv]
        return full, expect, out


_SWIM = ["swim", "evaluate", "--train", "{bvh}", "--test", "{bvh}", "--report", "{out}"]
_SYNTH = ["synth", "--procedural", "wave", "{out}"]
for _opt, _val in [("--camera-height", "-1"), ("--seed", "-1"), ("--seconds", "inf"), ("--seconds", "0"),
                   ("--fps", "0"), ("--fps", "nan"), ("--height", "1000"), ("--distance", "-2"),
                   ("--azimuth", "1e9"), ("--start", "-1"), ("--seed", "1.5")]:
    _arg_case(f"synth{_opt}={_val}", [*_SYNTH, f"{_opt}={_val}"], _opt)
for _opt, _val in [("--threads", "0"), ("--smooth", "-1"), ("--derivative", "d9"), ("--length", "0"),
                   ("--frames", "0"), ("--step", "-2"), ("--noise", "nan"), ("--seed", "-5"),
                   ("--temporal-sigma", "0"), ("--jitter", "-1")]:
    _arg_case(f"swim{_opt}={_val}", [*_SWIM, f"{_opt}={_val}"], _opt)
for _val in ("1e300", "-1", "nan", "0"):
    _arg_case(f"synth-units={_val}", ["synth", "{bvh}", "{out}", f"--units={_val}"], "motion.bvh")
_arg_case("swim-cycle-starts", [*_SWIM, "--cycle-starts", "5,3,99999"], "--cycle-starts")
_arg_case("swim-particles", [*_SWIM, "--particles", "0"], "--particles")
_arg_case("swim-sigma", [*_SWIM, "--sigma", "-1"], "--sigma")
_arg_case("swim-estimator", [*_SWIM, "--estimator", "median"], "median")
_arg_case("bench-seconds", ["bench", "--seconds", "-1"], "--seconds")
_arg_case("bench-tiles", ["bench", "--tiles", "48"], "--tiles")
_arg_case("bench-batches", ["bench", "--batches", "0"], "--batches")
_arg_case("bench-mesh", ["bench", "--mesh", "{out}/none.glb"], "none.glb: no such file")
_arg_case("bench-mesh-not-gltf", ["bench", "--mesh", "{bvh}"], "not a glTF file")
_arg_case("demo-seconds", ["demo", "--out", "{out}", "--seconds", "1e9"], "--seconds")
_arg_case("track-method", ["track", "{seq}", "-o", "{out}", "--method", "magic"], "--method")
_arg_case("track-no-out", ["track", "{seq}"], "-o")
_arg_case("eval-methods", ["eval", "{seq}", "--methods", "hc,magic", "--report", "{out}"], "magic")
_arg_case("unknown-command", ["dance"], "dance")


