"""How the kernels are loaded: the notice a first run prints while it compiles."""

from __future__ import annotations

import io
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
