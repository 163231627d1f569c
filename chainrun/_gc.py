"""Start-up phases without Python's cyclic garbage collector.

Starting a run imports pydantic, h5py and numba, and numba then loads the solver's
kernels: some hundreds of thousands of objects that live as long as the process and
hold almost no garbage. The collector walks them again and again while they are made,
about a tenth of a second of a warm ``chainrun simulate`` of a few balls.
``start_up`` stops it for such a phase and then moves everything alive into the
permanent generation (``gc.freeze``), which later collections do not walk.
"""

from __future__ import annotations

import contextlib
import gc

_done: set[str] = set()


@contextlib.contextmanager
def start_up(phase: str):
    """Run the block without automatic collections, then freeze what is alive.

    Only the first block of each ``phase`` in a process does so (imports and loading
    happen once; a process that runs the command again, like a test session, must
    not freeze its garbage each time); later ones run as they are. Collection is
    enabled again afterwards only if it was enabled before, so phases nest. Use it
    around start-up work (imports, loading compiled code), not around computations:
    garbage cycles made inside the block are never freed.
    """
    if phase in _done:
        yield
        return
    _done.add(phase)
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        gc.freeze()
        if enabled:
            gc.enable()
