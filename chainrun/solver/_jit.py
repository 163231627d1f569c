"""How the solver's kernels are compiled, cached and loaded.

Two decorators: ``kernel`` for functions called only from other kernels (no Python
wrapper, no cache entry of their own: their code is linked into the entry point that
calls them) and ``entry`` for what Python calls (cached; the solver has one,
``_loop.advance``, so that a run loads one library). Both are compiled
without numba's reference counting: the kernels allocate nothing.

The cache lives in a folder of its own, named by a hash of the kernels' sources (the
entry point's module and every solver module it imports) and of the compiler's versions
(``cache_dir``). numba's own cache notices a change in the file of an entry point but
not in a kernel it calls from another file, nor a change in the generated code; a folder
keyed by every source the kernels are made of cannot go stale. ``NUMBA_CACHE_DIR``, if
set, is where that folder goes; otherwise the user's cache folder.

Entry points compile with LLVM's SLP vectoriser on (numba leaves it off by default):
the series sums (``_series_orders``) write a tile's lanes out as scalars, which it
packs into vector instructions. No kernel takes ``fastmath`` flags, not even
``contract``: a product and a sum fused into one multiply-add round once instead of
twice, and only where the CPU has the instruction, so the answers would depend on the
machine's CPU (by 1e-13 of the velocity scale on a random line). Without them a build
for a generic x86-64 CPU gives this machine's answers bit for bit
(``tests/property/test_determinism.py``), and the kernels are 1-2% slower. ``prepare`` compiles (or loads) an entry point before
the clock of a run starts and tells the user on stderr when that means compiling.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import re
import sys
import threading
import time
from pathlib import Path

import numba as nb
from numba.core import config

#: a cold compile on a quiet 2-core machine of the kind CI runs on (the bench's section
#: compile measures it), for the message
COMPILE_ESTIMATE_S = 290
#: after this many seconds of loading, say that it is compiling, and every so often after
_NOTICE_AFTER_S = 2.0
_PROGRESS_EVERY_S = 10.0

# error_model "numpy": a float divided by zero is an IEEE infinity (or NaN), as numpy
# gives it, not a ZeroDivisionError out of the kernel; a product that underflows to 0
# (half of a subnormal relative acceleration) then divides into the limit the formula
# means, and the non-finite checks of the steps catch what is no number at all
_OPTIONS = dict(_nrt=False, error_model="numpy")
kernel = functools.partial(nb.njit, no_cpython_wrapper=True, no_cfunc_wrapper=True,
                           **_OPTIONS)


def entry(fn):
    """A kernel that Python calls: cached in ``cache_dir()``, compiled with SLP on.

    However its first call comes (``prepare`` or a direct call), what it compiles,
    and so caches, is the vectorised code.
    """
    with caching_into(cache_dir()):
        dispatcher = nb.njit(cache=True, **_OPTIONS)(fn)
    if config.DISABLE_JIT:  # (NUMBA_DISABLE_JIT=1: plain Python, to debug)
        return dispatcher
    compile_ = dispatcher.compile

    def compile(sig):
        with _slp_vectorised(), _without_blas_probe():
            return compile_(sig)

    dispatcher.compile = compile
    return dispatcher


#: the module whose ``entry`` Python calls; every kernel is reached from its imports
ENTRY_MODULE = "_loop"


#: an import of one of the package's modules, at any indentation (inside a function too)
_IMPORT = re.compile(r"^[ \t]*from chainrun\.solver\.(\w+) import", re.MULTILINE)


def kernel_sources(folder: Path = Path(__file__).parent) -> list[Path]:
    """The solver's files compiled into its entry point: ``ENTRY_MODULE`` and every
    module of the package it imports, directly or through another (found by reading
    their ``from chainrun.solver.X import`` lines, not by running them: a line like it
    in a docstring adds a file to the key, which costs a compile at worst)."""
    seen: dict[str, Path] = {}
    todo = [ENTRY_MODULE]
    while todo:
        name = todo.pop()
        path = folder / f"{name}.py"
        if name in seen or not path.exists():
            continue
        seen[name] = path
        todo.extend(_IMPORT.findall(path.read_text()))
    return sorted(seen.values())


def source_hash(folder: Path = Path(__file__).parent) -> str:
    """sha256 of the kernels' sources (``kernel_sources``) and of the Python, numba and
    llvmlite versions. A change in the solver's Python side (the driver, the model, the
    physics) keeps the compiled kernels."""
    import llvmlite

    h = hashlib.sha256()
    for path in kernel_sources(folder):
        h.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    versions = f"{sys.version_info[:3]} numba {nb.__version__} llvmlite {llvmlite.__version__}"
    h.update(versions.encode())
    return h.hexdigest()


def cache_root() -> Path:
    """Where the compiled kernels go: ``$NUMBA_CACHE_DIR``, else the user's cache folder."""
    env = os.environ.get("NUMBA_CACHE_DIR")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg else Path.home() / ".cache"
    return base / "chainrun"


@functools.cache
def cache_dir() -> Path:
    """The folder of this process's kernels (read once: the sources a process runs do not
    change under it)."""
    return cache_root() / f"kernels-{source_hash()[:16]}"


@contextlib.contextmanager
def caching_into(folder: Path):
    """numba's cache folder while the entry points are defined (their cache is made then)."""
    old = config.CACHE_DIR
    config.CACHE_DIR = str(folder)
    try:
        yield
    finally:
        config.CACHE_DIR = old


@contextlib.contextmanager
def _slp_vectorised():
    old = config.SLP_VECTORIZE
    config.SLP_VECTORIZE = 1
    try:
        yield
    finally:
        config.SLP_VECTORIZE = old


def _no_blas():
    raise ImportError("chainrun's kernels call no BLAS")


@contextlib.contextmanager
def _without_blas_probe():
    """numba's BLAS probe fails at once while an entry point compiles or loads.

    Before its first compile or cache load in a process, numba loads its
    implementations of numpy (``numba.np.arraymath``), which import ``scipy.linalg``
    (about 0.1 s, an eighth of a warm run's start-up) through
    ``numba.np.linalg.ensure_blas``, only to see whether ``np.convolve`` and
    ``np.correlate`` may call BLAS. No kernel calls BLAS: while numba loads them, that
    function raises at once, and numba uses its own loop there. It is numba's own again
    afterwards, for its linear algebra (``np.dot``, ``np.linalg``), which calls it when
    compiled; numba's compiler lock is held throughout, so no compile in another thread
    sees the stand-in, and no import anywhere is touched. Where numba's
    implementations are loaded already, or scipy's BLAS, nothing changes.
    """
    if "numba.np.arraymath" in sys.modules or "scipy.linalg" in sys.modules:
        yield
        return
    from numba.core.compiler_lock import global_compiler_lock
    from numba.np import linalg

    probe = getattr(linalg, "ensure_blas", None)
    if probe is None:  # (a numba that probes otherwise: it pays for its probe)
        yield
        return
    with global_compiler_lock:
        linalg.ensure_blas = _no_blas
        try:
            yield
        finally:
            linalg.ensure_blas = probe


def _cached(dispatcher, folder: Path) -> bool:
    """Whether the cache folder has an index for this entry point (a fast look, no load)."""
    name = dispatcher.py_func.__qualname__
    return any(folder.rglob(f"*.{name}-*.nbi"))


class _Notice:
    """Tells the user on stderr that the solver is being compiled, with the time so far."""

    def __init__(self, stream, now: bool):
        self.stream = stream
        self.t0 = time.perf_counter()
        self.said = False
        self.done = threading.Event()
        if now:
            self._say()
        self.thread = threading.Thread(target=self._watch, daemon=True)
        self.thread.start()

    def _say(self):
        self.said = True
        print(f"compiling the solver for this machine (first run only, about "
              f"{COMPILE_ESTIMATE_S} s)...", file=self.stream, flush=True)

    def _watch(self):
        if not self.said and not self.done.wait(_NOTICE_AFTER_S):
            self._say()
        while not self.done.wait(_PROGRESS_EVERY_S):
            print(f"  still compiling, {time.perf_counter() - self.t0:.0f} s so far",
                  file=self.stream, flush=True)

    def close(self):
        self.done.set()
        self.thread.join()
        if self.said:
            print(f"compiled in {time.perf_counter() - self.t0:.0f} s; later runs start at once",
                  file=self.stream, flush=True)


def prepare(dispatcher, *args, folder: Path | None = None, stream=None) -> bool:
    """Compile ``dispatcher`` for ``args``' types, or load it from the cache.

    Returns True if it was compiled or loaded now, False if it was ready already.
    """
    return prepare_all([(dispatcher, args)], folder=folder, stream=stream)


def prepare_all(entries, folder: Path | None = None, stream=None) -> bool:
    """``prepare`` for each (dispatcher, args) of ``entries``, under one notice to the
    user if any of them compiles."""
    if config.DISABLE_JIT:
        return False
    todo = []
    for dispatcher, args in entries:
        sig = tuple(nb.typeof(a) for a in args)
        if sig not in dispatcher.overloads:
            todo.append((dispatcher, sig))
    if not todo:
        return False
    folder = cache_dir() if folder is None else folder
    notice = _Notice(sys.stderr if stream is None else stream,
                     now=not all(_cached(dispatcher, folder) for dispatcher, _ in todo))
    try:
        for dispatcher, sig in todo:
            dispatcher.compile(sig)
    finally:
        notice.close()
    return True


@functools.cache
def python_twin(dispatcher):
    """A copy of a kernel that Python can call (tests and debugging), compiled on first use.

    ``kernel`` functions have no Python wrapper; this compiles the same function with one,
    outside the cache.
    """
    return nb.njit(**_OPTIONS)(dispatcher.py_func)
