"""Write a small Matroska file laid out as the Azure Kinect recorder does (test helper).

PyAV muxes the raw 16-bit big-endian frames as a VFW track; the track's FOURCC is then
set to ``b16g`` and its height made positive, as in files from the Azure Kinect recorder.
"""
from __future__ import annotations

import json
import struct

import numpy as np


def calibration_json(params) -> bytes:
    """An Azure Kinect calibration.json with a depth camera of the 14 given ModelParameters."""
    depth = {"Intrinsics": {"ModelParameterCount": 14, "ModelParameters": [float(p) for p in params],
                            "ModelType": "CALIBRATION_LensDistortionModelBrownConrady"},
             "Location": "CALIBRATION_CameraLocationD0", "Purpose": "CALIBRATION_CameraPurposeDepth",
             "SensorHeight": 1024, "SensorWidth": 1024}
    return json.dumps({"CalibrationInformation": {"Cameras": [depth]}}).encode()


def write_k4a_mkv(path, frames, mode: str, calibration: bytes, fps: float = 30.0):
    """``frames`` (F, H, W) uint16 millimetres -> ``path`` with a DEPTH track and the attachment."""
    import av

    frames = np.asarray(frames, dtype=np.uint16)
    f, h, w = frames.shape
    with av.open(str(path), "w", format="matroska", options={"allow_raw_vfw": "1"}) as out:
        stream = out.add_stream("rawvideo", rate=int(fps))
        stream.width, stream.height, stream.pix_fmt = w, h, "gray16be"
        stream.metadata["title"] = "DEPTH"
        stream.metadata["K4A_DEPTH_MODE"] = mode
        out.add_attachment("calibration.json", "application/octet-stream", calibration)
        for i, frame in enumerate(frames):
            vf = av.VideoFrame.from_ndarray(frame, format="gray16be")
            vf.pts = i
            for packet in stream.encode(vf):
                out.mux(packet)
        for packet in stream.encode():
            out.mux(packet)
    data = bytearray(open(path, "rb").read())
    header = struct.pack("<Iii", 40, w, -h)  # BITMAPINFOHEADER as PyAV writes it (top-down)
    at = data.find(header)
    assert at >= 0, "no BITMAPINFOHEADER found"
    data[at:at + 12] = struct.pack("<Iii", 40, w, h)
    data[at + 16:at + 20] = b"b16g"
    open(path, "wb").write(bytes(data))
    return path
