"""The process-wide OpenGL context (headless, over EGL) and shader loading.

One moderngl standalone context is created on first use and reused by every
renderer: creating a context costs about half a second and each one holds its own
copies of buffers and programs. EGL picks the GPU where there is one and Mesa's
llvmpipe software rasteriser otherwise. A forked child process gets a context of its
own on first use (GL objects made before the fork are not valid there). Use the context
from one thread at a time.
"""
from __future__ import annotations

import os
import re
from pathlib import Path

#: Where the GLSL sources live (``depthtrack/shaders/``, package data so that wheels carry them).
SHADER_DIR = Path(__file__).resolve().parents[1] / "shaders"

#: What to tell the user when headless OpenGL cannot be had.
EGL_HINT = "install Mesa EGL: apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri"

_CONTEXT = None
_CONTEXT_PID = None
_INCLUDE = re.compile(r'^\s*#include\s+"([^"]+)"\s*$', re.MULTILINE)


class GLUnavailableError(RuntimeError):
    """Headless OpenGL (EGL, GL >= 4.3) could not be started; the message says what to install."""


def gl_context():
    """The process-wide moderngl context (EGL, OpenGL >= 4.3 core), created once.

    Raises
    ------
    GLUnavailableError
        One line naming the packages to install when EGL or GL 4.3 is missing.
    """
    global _CONTEXT, _CONTEXT_PID
    if _CONTEXT is not None and _CONTEXT_PID != os.getpid():
        _CONTEXT = None     # a forked child cannot use its parent's context: make its own
    if _CONTEXT is None:
        try:
            import moderngl
        except ImportError:  # pragma: no cover - moderngl is a hard dependency
            raise GLUnavailableError("moderngl is not installed: pip install moderngl") from None
        try:
            _CONTEXT = moderngl.create_standalone_context(backend="egl", require=430)
            _CONTEXT_PID = os.getpid()
        except Exception as exc:  # moderngl/glcontext raise plain Exceptions
            reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise GLUnavailableError(f"headless OpenGL 4.3 over EGL is unavailable ({reason}); "
                                     f"{EGL_HINT}") from None
    return _CONTEXT


def gl_renderer() -> str:
    """The GL_RENDERER string of the shared context, e.g. ``'llvmpipe (LLVM 15.0.6, 256 bits)'``."""
    return gl_info()["gl_renderer"]


def gl_info() -> dict:
    """``{"gl_renderer", "gl_version"}`` of the shared context: which rasteriser drew (results
    differ in the last bits between rasterisers, and a tracker's outcome can follow them)."""
    info = gl_context().info
    return {"gl_renderer": info["GL_RENDERER"], "gl_version": info["GL_VERSION"]}


def shader_source(name: str) -> str:
    """Text of ``shaders/NAME`` with ``#include "other.glsl"`` lines expanded (one level deep)."""
    path = SHADER_DIR / name
    try:
        text = path.read_text()
    except OSError:
        raise GLUnavailableError(f"shader {path} is missing; reinstall depthtrack from its "
                                 f"source tree") from None
    return _INCLUDE.sub(lambda m: (SHADER_DIR / m.group(1)).read_text(), text)


def program(vertex: str | None = None, fragment: str | None = None):
    """Compile (and cache) a render program from shader file names."""
    ctx = gl_context()
    key = ("program", vertex, fragment)
    cache = ctx.extra if isinstance(ctx.extra, dict) else {}
    ctx.extra = cache
    if key not in cache:
        cache[key] = ctx.program(vertex_shader=shader_source(vertex),
                                 fragment_shader=shader_source(fragment) if fragment else None)
    return cache[key]


def compute(name: str, defines: dict | None = None):
    """Compile (and cache) a compute shader from ``shaders/NAME`` with ``#define`` lines added."""
    ctx = gl_context()
    defines = dict(defines or {})
    key = ("compute", name, tuple(sorted(defines.items())))
    cache = ctx.extra if isinstance(ctx.extra, dict) else {}
    ctx.extra = cache
    if key not in cache:
        source = shader_source(name)
        header, _, body = source.partition("\n")  # the #version line stays first
        lines = "".join(f"#define {k} {v}\n" for k, v in defines.items())
        cache[key] = ctx.compute_shader(f"{header}\n{lines}{body}")
    return cache[key]
