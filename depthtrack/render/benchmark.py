"""Throughput of the tiled candidate renderer: what ``depthtrack bench`` measures.

One "candidate" is a full :meth:`TileRenderer.costs` evaluation of one pose: skinning
matrices (numpy), upload, instanced render, per-pixel cost, reduction and read-back.
The scene is the default body in front of an SR4000-class camera; the observation is the
body rendered at a reference pose, segmented (background = inf) with 5 % missing readings,
and the candidates are random perturbations of that pose, as the tracker makes them.
"""
from __future__ import annotations

import os
import time

import numpy as np

from ..camera import Camera
from .context import gl_context, gl_info
from .frame import FrameRenderer
from .tiles import TileRenderer

TILES = (32, 64, 128)
BATCHES = (16, 64, 256, 1024)
#: GL_RASTERIZER_DISCARD: primitives are processed up to the rasteriser and dropped there.
GL_RASTERIZER_DISCARD = 0x8C89


def mipmap_is_box_mean(size: int = 64, seed: int = 0) -> bool:
    """Whether glGenerateMipmap on this driver gives the exact mean (rel. error <= 1e-4) of R32F texels.

    Informational: the cost pass does its own reduction and never relies on mipmaps.
    """
    ctx = gl_context()
    values = np.random.default_rng(seed).random((size, size)).astype(np.float32)
    texture = ctx.texture((size, size), 1, values.tobytes(), dtype="f4")
    try:
        texture.build_mipmaps()
        top = np.frombuffer(texture.read(level=int(np.log2(size))), np.float32)[0]
    finally:
        texture.release()
    return bool(abs(top - values.mean(dtype=np.float64)) <= 1e-4 * abs(values.mean()))


def _scene(body, camera: Camera, seed: int):
    pose = body.default_pose(position=(0.0, 0.1, 2.6))
    with FrameRenderer(camera) as frame:
        observed = frame.render(body, pose)
    observed[observed == 0] = np.inf
    observed[np.random.default_rng(seed).random(observed.shape) < 0.05] = 0.0
    uv = camera.project(body.joint_positions(pose))
    lo, hi = uv.min(axis=0), uv.max(axis=0)
    size = 1.3 * float(max(hi - lo))
    centre = (lo + hi) / 2
    roi = (centre[0] - size / 2, centre[1] - size / 2, size)
    return pose, observed, roi


def _timed(fn, seconds: float, min_calls: int = 3, cpu: bool = False):
    """Median wall seconds of one call of ``fn`` over at least ``seconds`` (after a warm-up).

    With ``cpu``, also the median process CPU seconds per call (all threads, llvmpipe's
    included): unlike wall time it hardly changes when other programs load the machine.
    """
    fn()
    times, cpu_times = [], []
    start = time.perf_counter()
    while len(times) < min_calls or time.perf_counter() - start < seconds:
        t, c = time.perf_counter(), time.process_time()
        fn()
        times.append(time.perf_counter() - t)
        cpu_times.append(time.process_time() - c)
    if cpu:
        return float(np.median(times)), float(np.median(cpu_times))
    return float(np.median(times))


def _bench_body(mesh: str):
    """The default body with the shipped mesh ``mesh`` names (``DEFAULT_MESH_FILES``), or
    with the skinned glTF at path ``mesh`` (:class:`~depthtrack.errors.InputError` naming the
    file when it is not a mesh of the default skeleton)."""
    from ..body import BodyModel
    from ..body.gltf import load_skinned_gltf
    from ..body.model import DEFAULT_MESH_FILES
    from ..errors import InputError

    if mesh in DEFAULT_MESH_FILES:
        return BodyModel.default(mesh=mesh)
    body = BodyModel.default()
    skinned = load_skinned_gltf(mesh).mesh
    if len(skinned.inverse_bind) != len(body.mesh.inverse_bind):
        raise InputError(mesh, f"skinned to {len(skinned.inverse_bind)} joints; the default "
                               f"body has {len(body.mesh.inverse_bind)}")
    return body.with_mesh(skinned)


def benchmark_tiles(mesh: str = "decimated", tiles=TILES, batches=BATCHES, seconds: float = 0.5,
                    smoothed: bool = True, seed: int = 0, progress=None) -> dict:
    """Candidates per second of :meth:`TileRenderer.costs` per tile size and batch size.

    Parameters
    ----------
    mesh : {"decimated", "coarse", "full"} or path
        A shipped level of detail, or a skinned glTF of the default skeleton (e.g. one
        built by ``tools/make_body_mesh.py --decimated 500 --out DIR``: another triangle
        count).
    tiles, batches : sequences of int
    seconds : float
        Wall time spent timing each (tile, batch) cell; the median call is reported.
    smoothed : bool
        Smoothed likelihood (the tracker's default) or the pixel-wise cost.
    progress : Progress, optional
        Advanced once per cell.

    Returns
    -------
    dict
        ``gl_renderer``, ``gl_version``, ``mesh`` (name, vertices, triangles), ``results``
        (one row per cell: tile, batch, candidates_per_s, ms_per_call, cpu_us_per_candidate)
        and ``breakdown`` (per tile at the largest batch: CPU milliseconds in skinning
        matrices, upload + render, cost pass + reduction + read-back; and
        ``geometry_cpu_ms``, the part of upload + render left with every primitive dropped
        at the rasteriser: vertex shader, clipping, primitive assembly).
    """
    ctx = gl_context()
    body = _bench_body(mesh)
    camera = Camera.preset("sr4000")
    pose, observed, roi = _scene(body, camera, seed)
    rng = np.random.default_rng(seed)
    results, breakdown = [], []
    cull = None
    for tile in tiles:
        renderer = TileRenderer(body, camera, tile=tile)
        cull = renderer.cull_back_faces
        renderer.set_observation(observed, roi=roi)
        for batch in batches:
            poses = np.repeat(pose[None], batch, axis=0)
            poses[:, 3:] += rng.normal(0.0, 0.1, (batch, poses.shape[1] - 3))
            poses[:, :3] += rng.normal(0.0, 0.02, (batch, 3))
            per_call, cpu = _timed(lambda: renderer.costs(poses, smoothed=smoothed), seconds,
                                   cpu=True)
            results.append(dict(tile=tile, batch=batch, candidates_per_s=batch / per_call,
                                ms_per_call=1e3 * per_call,
                                cpu_us_per_candidate=1e6 * cpu / batch))
            if progress is not None:
                progress.update(1, note=f"tile {tile} batch {batch}")
        # where the time goes at the largest batch, in CPU time (robust to other load)
        _, skin = _timed(lambda: body.skin_matrices(poses), seconds / 3, cpu=True)

        def render_only():
            renderer._upload_bones(poses)
            for first, count, grid in renderer._passes(len(poses)):
                renderer._draw(first, count, grid)
            renderer._fbo.read(viewport=(0, 0, 1, 1), components=1, dtype="f4")  # waits for it
        _, render = _timed(render_only, seconds / 3, cpu=True)

        def vertices_only():
            # the same draws with every primitive dropped at the rasteriser: what is left is
            # the geometry's work (vertex shader, clipping, primitive assembly)
            ctx.enable_direct(GL_RASTERIZER_DISCARD)
            try:
                render_only()
            finally:
                ctx.disable_direct(GL_RASTERIZER_DISCARD)
        _, geometry = _timed(vertices_only, seconds / 3, cpu=True)
        # the cost pass alone, on the atlas of the last pass that render_only left behind
        _, last_count, last_grid = list(renderer._passes(len(poses)))[-1]
        program = renderer._cost_program(smoothed)

        def cost_only():
            renderer._costs.bind_to_storage_buffer(1)
            renderer._atlas.use(0)
            renderer._observed.use(1)
            program["u_first"].value = 0
            program["u_grid"].value = last_grid
            program.run(group_x=last_count)
            ctx.memory_barrier()
            renderer._costs.read(size=4 * last_count)
        _, cost = _timed(cost_only, seconds / 3, cpu=True)
        total = results[-1]["cpu_us_per_candidate"] * len(poses) / 1e6
        breakdown.append(dict(tile=tile, batch=len(poses), skin_cpu_ms=1e3 * skin,
                              render_cpu_ms=1e3 * (render - skin),
                              geometry_cpu_ms=1e3 * max(geometry - skin, 0.0),
                              cost_cpu_ms=1e3 * cost * len(poses) / last_count,
                              total_cpu_ms=1e3 * total))
        renderer.release()
    return dict(**gl_info(),
                mesh=dict(name=str(mesh), vertices=int(len(body.mesh.vertices)),
                          triangles=int(len(body.faces))),
                back_faces_culled=bool(cull), smoothed=bool(smoothed),
                camera="sr4000 176x144", roi=[round(float(x), 1) for x in roi],
                cpu_count=os.cpu_count(), load_average=[round(x, 2) for x in os.getloadavg()],
                mipmap_is_box_mean=mipmap_is_box_mean(),
                results=results, breakdown=breakdown)


def format_report(report: dict) -> str:
    """Human-readable table of :func:`benchmark_tiles`'s result."""
    mesh = report["mesh"]
    batches = sorted({r["batch"] for r in report["results"]})
    tiles = sorted({r["tile"] for r in report["results"]})
    rate = {(r["tile"], r["batch"]): r["candidates_per_s"] for r in report["results"]}
    lines = [
        f"GL_RENDERER: {report['gl_renderer']} ({report['gl_version']})",
        f"mesh: {mesh['name']}, {mesh['vertices']} vertices, {mesh['triangles']} triangles"
        f"{' (back faces culled)' if report['back_faces_culled'] else ''}; "
        f"{'smoothed' if report['smoothed'] else 'pixel-wise'} likelihood; "
        f"camera {report['camera']}, ROI {report['roi']}",
        "candidates per second (skinning + upload + render + cost + reduction + read-back):",
        "tile \\ batch" + "".join(f"{b:>9d}" for b in batches),
    ]
    for t in tiles:
        lines.append(f"{t:>12d}" + "".join(f"{rate.get((t, b), float('nan')):>9.0f}" for b in batches))
    cpu = {(r["tile"], r["batch"]): r["cpu_us_per_candidate"] for r in report["results"]}
    lines.append(f"CPU microseconds per candidate, all threads (robust to other load; "
                 f"{report['cpu_count']} cores, load average {report['load_average'][0]}):")
    for t in tiles:
        lines.append(f"{t:>12d}" + "".join(f"{cpu.get((t, b), float('nan')):>9.0f}" for b in batches))
    lines.append("where the time goes (CPU ms per call at the largest batch):")
    for b in report["breakdown"]:
        lines.append(f"  tile {b['tile']:>3d} x {b['batch']}: skinning matrices (numpy) "
                     f"{b['skin_cpu_ms']:.1f}, upload + render {b['render_cpu_ms']:.1f} "
                     f"(of which geometry {b['geometry_cpu_ms']:.1f}), "
                     f"cost pass + reduction + read-back {b['cost_cpu_ms']:.1f} "
                     f"(timed apart); whole costs() call {b['total_cpu_ms']:.1f}")
    lines.append(f"glGenerateMipmap is an exact box mean on this driver: "
                 f"{'yes' if report['mipmap_is_box_mean'] else 'no'} (not relied on: the cost "
                 f"pass reduces each tile itself)")
    return "\n".join(lines)
