"""How the kernels are loaded: the notice a first run prints while it compiles, and what
loading them imports."""

from __future__ import annotations

import io
import subprocess
import sys
import time

from chainrun.solver import _jit


class _Slow:
    """Stands for an entry point whose compile (or load) takes ``seconds``."""

    def __init__(self, seconds: float):
        self.seconds = seconds
        self.overloads = {}

        def advance(S):
            return S

        advance.__qualname__ = "advance"
        self.py_func = advance

    def compile(self, sig):
        time.sleep(self.seconds)
        self.overloads[sig] = object()


def _prepare(tmp_path, seconds, cached):
    if cached:
        (tmp_path / "solver_0").mkdir(exist_ok=True)
        (tmp_path / "solver_0" / "_loop.advance-12.py311.nbi").write_bytes(b"")
    out = io.StringIO()
    entry = _Slow(seconds)
    assert _jit.prepare(entry, 1.0, folder=tmp_path, stream=out)
    assert not _jit.prepare(entry, 1.0, folder=tmp_path, stream=out)  # ready: silent
    return out.getvalue()


def test_a_cold_cache_is_announced_at_once_and_its_end_told(tmp_path):
    text = _prepare(tmp_path, 0.0, cached=False)
    lines = text.splitlines()
    assert lines[0].startswith("compiling the solver for this machine (first run only")
    assert lines[-1].startswith("compiled in ")


def test_a_warm_cache_loads_silently(tmp_path):
    assert _prepare(tmp_path, 0.0, cached=True) == ""


def test_a_load_that_takes_long_is_announced_with_progress(tmp_path, monkeypatch):
    monkeypatch.setattr(_jit, "_NOTICE_AFTER_S", 0.05)
    monkeypatch.setattr(_jit, "_PROGRESS_EVERY_S", 0.1)
    text = _prepare(tmp_path, 0.45, cached=True)
    assert text.startswith("compiling the solver")
    assert "still compiling" in text
    assert text.splitlines()[-1].startswith("compiled in ")


def test_loading_the_kernels_leaves_scipys_blas_alone(tmp_path):
    # numba probes for scipy's BLAS (about 0.1 s of imports) before its first load; the
    # kernels need none, and numba's own linear algebra still finds it afterwards
    code = """
import sys
import numba
import numpy as np
from chainrun.solver import load_kernels
load_kernels()
print("scipy.linalg" in sys.modules)
dot = numba.njit(lambda a, b: np.dot(a, b))
convolve = numba.njit(lambda a, b: np.convolve(a, b))
a = np.array([1.0, 2.0, 3.0])
b = np.array([0.5, -1.0])
print(dot(a, a), convolve(a, b).tolist())
import scipy.linalg
print(scipy.linalg.solve(np.eye(2), np.ones(2)).tolist())
"""
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, check=True)
    assert done.stdout.split("\n")[:3] == [
        "False", "14.0 [0.5, 0.0, -0.5, -3.0]", "[1.0, 1.0]"], done.stdout + done.stderr
