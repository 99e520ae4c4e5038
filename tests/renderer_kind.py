"""Which rasteriser the tests run on (a helper module, like ``detect_frames.py``)."""


def software_renderer() -> bool:
    """True when GL renders with Mesa's llvmpipe (CI, and every machine without a GPU).

    A few tests pin numbers that were recorded there, or need a hill climb to stay in a
    local minimum it stays in there; a GPU's rasteriser rounds differently at triangle
    seams, and those tests say so where they skip or are expected to fail.
    """
    from depthtrack.render.context import gl_renderer

    return "llvmpipe" in gl_renderer().lower()
