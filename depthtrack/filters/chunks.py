"""Chunked, threaded evaluation of row-wise work over many particles."""
from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor


def run_chunked(n: int, fn, chunk: int = 16384, threads: int = 2):
    """Call ``fn(start, stop, chunk_index)`` over ``range(n)`` in chunks, on ``threads`` threads.

    Chunks of a few thousand rows keep the working arrays in cache; numpy releases
    the GIL inside its kernels, so two threads use two cores. ``chunk_index`` lets
    each chunk seed its own random stream, so results do not depend on ``threads``.
    """
    bounds = [(a, min(a + chunk, n), i) for i, a in enumerate(range(0, n, chunk))]
    if threads <= 1 or len(bounds) <= 1:
        for a, b, i in bounds:
            fn(a, b, i)
        return
    with ThreadPoolExecutor(threads) as pool:
        for _ in pool.map(lambda t: fn(*t), bounds):
            pass
