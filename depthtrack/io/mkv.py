"""Azure Kinect (and Orbbec Femto, whose recorder writes the same layout) ``.mkv`` files,
read with PyAV; no vendor SDK.

Depth is the video track titled ``DEPTH`` (codec ``b16g``: 16-bit big-endian
millimetres, 0 = no reading). Frame times are the track's presentation times, in seconds
from the start of the recording. The intrinsics are those of the ``calibration.json``
attachment's depth camera, for the recorded ``K4A_DEPTH_MODE``, computed as the Azure
Kinect SDK does (``transformation_get_mode_specific_depth_camera_calibration``): the
calibration is stored normalised to the 1024 x 1024 sensor, so for mode M with binned
sensor size ``(bw, bh)``, crop offset ``(ox, oy)`` and output size ``(w, h)``::

    fx = fx_n * bw,  fy = fy_n * bh,  cx = cx_n * bw - ox - 0.5,  cy = cy_n * bh - oy - 0.5

(the 0.5 moves the origin from the corner to the centre of the top-left pixel).

Lens distortion (the calibration's Brown-Conrady model, which is OpenCV's rational model
with coefficients k1..k6, p1, p2) is strong in the wide-FOV modes: with
``undistort="auto"`` (default) WFOV frames are resampled (nearest neighbour, so depths are
never blended across edges) onto the pinhole camera with the same fx, fy, cx, cy, which
keeps the central part of the 120-degree field (about 90 degrees across) and drops the
rim. NFOV frames are passed through as recorded, with the pinhole part of the
calibration as their camera; their distortion is not small away from the centre (on the
shared NFOV recording: under 4 px within 100 px of the principal point, median 14 px and
up to 61 px over the valid pixels), so ``undistort=True`` is the better choice for
tracking a person who fills the frame. ``undistort=True`` or ``False`` forces either
for any mode.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..camera import Camera
from ..errors import InputError
from .arrays import RecordingSequence
from .registry import Reader, fps_from_timestamps
from .validation import finite_positive as positive

#: K4A depth modes: (binned calibration resolution, crop offset, output resolution),
#: the Azure Kinect SDK's table for a 1024 x 1024 depth sensor.
DEPTH_MODES = {
    "NFOV_2X2BINNED": ((512, 512), (96, 90), (320, 288)),
    "NFOV_UNBINNED": ((1024, 1024), (192, 180), (640, 576)),
    "WFOV_2X2BINNED": ((512, 512), (0, 0), (512, 512)),
    "WFOV_UNBINNED": ((1024, 1024), (0, 0), (1024, 1024)),
    "PASSIVE_IR": ((1024, 1024), (0, 0), (1024, 1024)),
}
_EBML_MAGIC = b"\x1a\x45\xdf\xa3"


def depth_calibration(calibration: dict, path=None) -> dict:
    """The depth camera's entry of an Azure Kinect ``calibration.json``.

    Returns
    -------
    dict
        ``params`` (14,) float as stored (cx, cy, fx, fy normalised, k1..k6, codx, cody,
        p2, p1), ``sensor`` (width, height), ``model`` (str).
    """
    try:
        cameras = calibration["CalibrationInformation"]["Cameras"]
        cam = next(c for c in cameras if c.get("Purpose") == "CALIBRATION_CameraPurposeDepth")
        params = np.asarray(cam["Intrinsics"]["ModelParameters"], dtype=float)
        sensor = (int(cam["SensorWidth"]), int(cam["SensorHeight"]))
        model = str(cam["Intrinsics"].get("ModelType", ""))
    except (KeyError, TypeError, ValueError, StopIteration):
        raise InputError(path, "calibration.json has no depth camera intrinsics") from None
    if params.size < 14:
        raise InputError(path, f"calibration.json: depth camera has {params.size} model parameters, 14 expected")
    return {"params": params[:14], "sensor": sensor, "model": model}


def mode_intrinsics(params, mode: str, sensor=(1024, 1024), path=None):
    """Pinhole intrinsics and distortion of a K4A depth mode, as the Azure Kinect SDK derives them.

    Parameters
    ----------
    params : (14,) float
        The calibration's ModelParameters (normalised cx, cy, fx, fy first).
    mode : str
        ``K4A_DEPTH_MODE`` tag, e.g. ``"NFOV_UNBINNED"``.
    sensor : (int, int)
        The calibration's sensor size (the SDK requires 1024 x 1024).

    Returns
    -------
    camera : Camera
    distortion : (8,) float
        OpenCV order ``k1, k2, p1, p2, k3, k4, k5, k6``.
    """
    if mode not in DEPTH_MODES:
        raise InputError(path, f"unknown depth mode {mode!r} (known: {', '.join(DEPTH_MODES)})")
    if tuple(sensor) != (1024, 1024):
        raise InputError(path, f"depth calibration is for a {sensor[0]} x {sensor[1]} sensor; the "
                               "depth modes are defined for 1024 x 1024")
    (bw, bh), (ox, oy), (w, h) = DEPTH_MODES[mode]
    cx_n, cy_n, fx_n, fy_n = params[:4]
    camera = Camera(width=w, height=h, fx=float(fx_n * bw), fy=float(fy_n * bh),
                    cx=float(cx_n * bw - ox - 0.5), cy=float(cy_n * bh - oy - 0.5))
    k1, k2, k3, k4, k5, k6, _codx, _cody, p2, p1 = params[4:14]
    return camera, np.array([k1, k2, p1, p2, k3, k4, k5, k6], dtype=float)


def undistort_maps(camera: Camera, distortion):
    """(H, W) float32 x and y source maps that resample a distorted frame onto ``camera``."""
    import cv2

    return cv2.initUndistortRectifyMap(camera.matrix, np.asarray(distortion, float), None,
                                       camera.matrix, (camera.width, camera.height), cv2.CV_32FC1)


def _depth_stream(container, path):
    for s in container.streams.video:
        if str(s.metadata.get("title", "")).upper() == "DEPTH":
            return s
    titles = [str(s.metadata.get("title", "?")) for s in container.streams.video]
    raise InputError(path, f"no video track titled DEPTH (tracks: {', '.join(titles) or 'none'}); "
                           "not an Azure Kinect / Femto recording")


def _calibration(container, path):
    for s in container.streams:
        if s.type == "attachment" and str(s.metadata.get("filename", "")) == "calibration.json":
            try:
                return json.loads(bytes(s.data))
            except (ValueError, UnicodeDecodeError) as exc:
                raise InputError(path, f"calibration.json attachment is not JSON ({exc})") from None
    return None


def _open_container(path):
    import av

    try:
        return av.open(str(path))
    except (av.FFmpegError, OSError) as exc:
        raise InputError(path, f"cannot read as Matroska ({exc})") from None


class MkvSequence(RecordingSequence):
    """The depth track of an Azure Kinect / Femto recording (frames decoded in batches)."""

    def __init__(self, path, pts, time_base, size, camera, fps, depth_scale, meta, maps=None):
        super().__init__(path, camera, fps, depth_scale, np.asarray(pts, dtype=float) * time_base, meta)
        self._pts = np.asarray(pts, dtype=np.int64)
        self._size = size            # (W, H) as stored
        self._maps = maps            # undistortion maps or None

    def _decode(self, packet) -> np.ndarray:
        w, h = self._size
        data = bytes(packet)
        if len(data) != w * h * 2:
            raise InputError(self.path, f"DEPTH packet at {packet.pts} holds {len(data)} bytes, "
                                        f"{w * h * 2} expected for {w} x {h} b16g")
        raw = np.frombuffer(data, dtype=">u2").reshape(h, w).astype(np.uint16)
        if self._maps is not None:
            import cv2

            raw = cv2.remap(raw, self._maps[0], self._maps[1], cv2.INTER_NEAREST,
                            borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        return raw

    def _read(self, start, stop):
        wanted = {int(p): k for k, p in enumerate(self._pts[start:stop])}
        frames = [None] * (stop - start)
        container = _open_container(self.path)
        try:
            stream = _depth_stream(container, self.path)
            container.seek(int(self._pts[start]), stream=stream, backward=True, any_frame=True)
            for packet in container.demux(stream):
                if packet.pts is None or packet.size == 0:
                    continue
                k = wanted.get(int(packet.pts))
                if k is not None and frames[k] is None:
                    frames[k] = self._decode(packet)
                if packet.pts >= self._pts[stop - 1]:
                    break
        finally:
            container.close()
        if any(f is None for f in frames):
            missing = start + next(k for k, f in enumerate(frames) if f is None)
            raise InputError(self.path, f"DEPTH frame {missing} could not be read back")
        return frames


def open_mkv(path, undistort="auto", depth_units=None, fps=None, intrinsics=None) -> MkvSequence:
    """Open the depth track of an Azure Kinect / Femto ``.mkv`` (see the module docstring).

    Parameters
    ----------
    undistort : {"auto", True, False}
        Resample onto the pinhole camera: "auto" does it for WFOV modes only.
    depth_units : float, optional
        Metres per unit (default 0.001: the recorder writes millimetres).
    intrinsics : str, optional
        Replaces the calibration's camera (no undistortion then, unless asked for).
    """
    path = Path(path)
    container = _open_container(path)
    try:
        stream = _depth_stream(container, path)
        if stream.codec_tag != "b16g":
            raise InputError(path, f"DEPTH track has codec {stream.codec_tag!r}, not b16g")
        size = (int(stream.codec_context.width), int(stream.codec_context.height))
        mode = str(stream.metadata.get("K4A_DEPTH_MODE", ""))
        calibration = _calibration(container, path)
        time_base = float(stream.time_base)
        rate = stream.average_rate or stream.guessed_rate
        tags = {k: v for k, v in container.metadata.items() if k.startswith("K4A_")}
        pts = sorted(int(p.pts) for p in container.demux(stream) if p.pts is not None and p.size > 0)
    finally:
        container.close()
    if not pts:
        raise InputError(path, "DEPTH track holds no frames")
    source = {"format": "azure-kinect-mkv", "input": str(path), "depth_mode": mode or None,
              "device_serial": tags.get("K4A_DEVICE_SERIAL_NUMBER"), "tags": tags}
    distortion = None
    if intrinsics is not None:
        from .registry import parse_intrinsics

        camera = parse_intrinsics(intrinsics, size[0], size[1], path)
        source["intrinsics_from"] = "given"
    else:
        if calibration is None:
            raise InputError(path, "no calibration.json attachment: give --intrinsics fx,fy,cx,cy")
        if not mode:
            raise InputError(path, "DEPTH track has no K4A_DEPTH_MODE tag: give --intrinsics fx,fy,cx,cy")
        cal = depth_calibration(calibration, path)
        camera, distortion = mode_intrinsics(cal["params"], mode, cal["sensor"], path)
        if camera.shape != size[::-1]:
            raise InputError(path, f"DEPTH frames are {size[0]} x {size[1]}, mode {mode} is "
                                   f"{camera.width} x {camera.height}")
        source["intrinsics_from"] = f"calibration.json, {mode}"
        source["distortion"] = distortion.tolist()
        source["distortion_model"] = cal["model"]
    if undistort == "auto":
        undistort = mode.startswith("WFOV") and intrinsics is None
    if undistort and distortion is None:
        raise InputError(path, "cannot undistort without the calibration's distortion (intrinsics were given)")
    source["undistorted"] = bool(undistort)
    maps = undistort_maps(camera, distortion) if undistort else None
    scale = 0.001 if depth_units is None else positive(depth_units, "depth units", path)
    t = np.asarray(pts, dtype=float) * time_base
    default_fps = float(rate) if rate else 30.0
    frame_rate = positive(fps, "fps", path) if fps is not None else fps_from_timestamps(t, default_fps)
    return MkvSequence(path, pts, time_base, size, camera, frame_rate, scale, {"source": source}, maps)


def _is_k4a_mkv(path, head) -> bool:
    return head.startswith(_EBML_MAGIC)


READERS = {
    "azure-kinect-mkv": Reader(
        "azure-kinect-mkv", open_mkv, suffixes=(".mkv",), sniff=_is_k4a_mkv,
        options=("undistort", "depth_units", "fps", "intrinsics"),
        description="Azure Kinect / Orbbec Femto .mkv (DEPTH track, calibration.json)"),
}
