"""The same OpenBLAS kernels on every x86-64 machine (depthtrack.environment.pin_blas_kernels)."""
import json
import os
import subprocess
import sys

import pytest

from depthtrack.environment import BLAS_CORE, _cpu_flags, pin_blas_kernels

AVX2 = {"avx2", "fma"} <= (_cpu_flags() or set())


@pytest.mark.parametrize("environ, modules, flags, reason, pinned", [
    ({}, {}, {"avx2", "fma", "sse2"}, "pinned", True),
    ({"OPENBLAS_CORETYPE": "Zen"}, {}, {"avx2", "fma"}, "OPENBLAS_CORETYPE set", False),
    ({"DEPTHTRACK_BLAS": "native"}, {}, {"avx2", "fma"}, "DEPTHTRACK_BLAS=native", False),
    ({}, {"numpy": object()}, {"avx2", "fma"}, "numpy imported first", False),
    ({}, {}, {"sse2", "avx"}, "no AVX2 and FMA", False),
    ({}, {}, set(), "no AVX2 and FMA", False),           # not x86-64 (an ARM CPU)
])
def test_pin_only_where_it_can_take_and_nobody_chose(environ, modules, flags, reason, pinned):
    env = dict(environ)
    assert pin_blas_kernels(env, modules, flags) == reason
    assert (env.get("OPENBLAS_CORETYPE") == BLAS_CORE) == pinned
    # the user's own choice is never overwritten
    if "OPENBLAS_CORETYPE" in environ:
        assert env["OPENBLAS_CORETYPE"] == environ["OPENBLAS_CORETYPE"]


PROBE = """
import json, sys
{first}
import depthtrack
from depthtrack.environment import blas_kernels
import numpy as np
rng = np.random.default_rng(0)
a, b = rng.normal(size=(97, 61)), rng.normal(size=(61, 83))
print(json.dumps({{**blas_kernels(), "product": (a @ b).tobytes().hex()}}))
"""


def _probe(first="", **env):
    """One fresh Python: its kernels (``blas_kernels``) and a matrix product's bits."""
    clean = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_CORETYPE", "DEPTHTRACK_BLAS")}
    out = subprocess.run([sys.executable, "-c", PROBE.format(first=first)], capture_output=True,
                         text=True, env={**clean, **env}, check=True).stdout
    return json.loads(out)


@pytest.mark.skipif(not AVX2, reason="pins only on x86-64 with AVX2 and FMA")
def test_import_depthtrack_first_pins_every_openblas_and_says_so():
    pinned = _probe()
    assert pinned["pin"] == "pinned" and pinned["coretype"] == BLAS_CORE
    archs = {lib["architecture"] for lib in pinned["libraries"]}
    assert archs == {BLAS_CORE}, pinned["libraries"]
    # the same product as a process told the kernels outright, whatever this CPU would pick
    told = _probe(OPENBLAS_CORETYPE=BLAS_CORE)
    assert told["pin"] == "OPENBLAS_CORETYPE set"
    assert pinned["product"] == told["product"]
    # on a CPU with AVX-512 OpenBLAS's own choice sums otherwise (3.5 % of these entries
    # differ in the last bits there), which is what the pin is for
    if "avx512f" in (_cpu_flags() or set()):
        assert _probe(DEPTHTRACK_BLAS="native")["product"] != pinned["product"]
    # numpy first: too late, and said so
    late = _probe(first="import numpy")
    assert late["pin"] == "numpy imported first" and late["coretype"] is None


@pytest.mark.skipif(not AVX2, reason="pins only on x86-64 with AVX2 and FMA")
def test_the_suite_runs_pinned_like_the_command_line():
    """conftest.py imports depthtrack before numpy, so the tests' tracks use the kernels the
    command line's do (unless the person running them chose otherwise)."""
    from depthtrack import environment
    assert environment.BLAS_PIN in ("pinned", "OPENBLAS_CORETYPE set", "DEPTHTRACK_BLAS=native")


def test_no_pin_where_the_cpu_cannot_be_read(monkeypatch):
    from depthtrack import environment
    monkeypatch.setattr(environment, "_cpu_flags", lambda: None)     # not Linux
    env = {}
    assert environment.pin_blas_kernels(env, {}) == "CPU not read" and not env
