"""Resource limits: will a run fit in this machine's memory, and its file on the disk?

This module owns the estimates of what a run needs, made before anything is computed,
so that a run too large for the machine is refused up front with the numbers, not
killed by the kernel's out-of-memory handler half-way through. It reads only
``/proc/meminfo`` (or ``os.sysconf``) and ``shutil.disk_usage``; it imports neither the
solver nor h5py.

Memory (``estimate_run_memory``) counts the solver's state arrays of length N
(``chainrun.solver._setup._new_state``: about twenty float64 and int64 arrays, one per
ball, contact or cluster), the compact window of integrated balls, one snapshot and the
results being written, and the snapshot times. Snapshots are streamed to the run file
as they are taken, so their number does not multiply the memory by N.

Disk (``estimate_file_size``) counts the snapshots before compression, ``T * N * 2 * 8``
bytes for positions and velocities, plus the per-ball results. Compression often
shrinks this a lot (balls at rest compress to almost nothing), so a file larger than
the free space is reported as a warning, not refused; so is output above
``LARGE_OUTPUT`` (1 GiB), with what would keep it small. While it writes, the run file
stops the run before it fills the disk (``chainrun.store.run_writer.DISK_RESERVE``).
"""

from __future__ import annotations

import math
import os
import shutil
from pathlib import Path

from chainrun.errors import ChainrunError

__all__ = [
    "check_disk",
    "check_memory",
    "check_runs",
    "estimate_file_size",
    "estimate_run_memory",
    "free_disk",
    "human_size",
    "memory_available",
]

#: Bytes per ball of the solver's state (``_setup._new_state``): float64 ``bx, bv, bt,
#: sep_t, sep_v, ox, ov`` and int64 ``bmap, jbuf`` (9 x 8), the heap ``hp_t, hp_j,
#: hp_s`` (3N each: 9 x 8), ``freed`` (2N int64: 16), one contact per ball (``cst``
#: int8, ``lvl`` float64, ``stamp`` int64: 17), N/2 clusters (``clo, chi, coff`` int64
#: and ``cen`` float64: 16), and the balls' and contacts' parameters (``bp``: 3 x 8,
#: ``cp``: 5 x 8; 9 x 8 on a damped line) with the sealed collisions' closed forms
#: (``sl``: 6 x 8).
STATE_BYTES_PER_BALL = 9 * 8 + 9 * 8 + 16 + 17 + 16 + 3 * 8 + 5 * 8 + 6 * 8
#: Bytes per ball more on a damped line: ``cp`` has 9 rows (4 x 8 more: damping, its
#: exponent, the held state and the energy dissipated) and ``sl`` 11 (5 x 8 more).
DAMPED_BYTES_PER_BALL = 4 * 8 + 5 * 8
#: Bytes per ball of the window of integrated balls (``_setup._alloc_window``): ``cb``,
#: ``X, V, A, X0, V0, A0, XS, FS, DM`` (10 x 8), ``KV`` (16 stages and 2 rows of a damped
#: line's x 8), ``FX, FV`` (2 x 7 x 8), the Taylor series ``TX`` (25 orders x 8), its work
#: tiles ``TW`` (51 rows x 8), lane stiffnesses ``TR`` (8) and the balls' and lanes'
#: parameters ``WP`` (7 x 8).
WINDOW_BYTES_PER_BALL = 10 * 8 + 18 * 8 + 2 * 7 * 8 + (25 + 51 + 1) * 8 + 7 * 8
#: Output above this many bytes before compression is worth a word before the run
#: starts, even where the disk holds it: snapshots every nanosecond of a millisecond
#: are more often a slip of units than a wish.
LARGE_OUTPUT = 2**30
#: Initial window (``_setup._INITIAL_WINDOW``); it grows with the width of the
#: compressed region, which stays far below N (about N**(1/3) for alpha = 1).
WINDOW_MIN = 256
#: Bytes per ball of one snapshot in flight and the results: the observables'
#: temporaries and HDF5's conversion buffer (5 x 8), the final state and separation
#: arrays copied into the Solution (4 x 8) and their copies as they are written (4 x 8).
OUTPUT_BYTES_PER_BALL = 13 * 8
#: Bytes per snapshot time: the times in the run spec and the solver (2 x 8), and in
#: the resolved config kept as a list and JSON text (about 40).
BYTES_PER_TIME = 56
#: Bytes per force sample of one sensor (a sample time by a sensor ball): the positions
#: and velocities of its ball and two neighbours (6 x 8), in buffers that double as
#: they fill (so twice that at worst), and its two forces and their mean (3 x 8) as
#: they are written.
BYTES_PER_SAMPLE = 2 * 6 * 8 + 3 * 8
#: Fixed buffers: the solver's event buffer (2**16 events of 17 bytes, and a copy as it
#: is flushed) and HDF5's chunk caches (1 MiB for each of a dozen datasets).
FIXED_BYTES = 2 * (1 << 16) * 17 + 12 * (1 << 20)

_MEMINFO = "/proc/meminfo"


def human_size(nbytes: float) -> str:
    """``nbytes`` for a person: ``"1.5 GB"`` (powers of 1000, like ``df -H``)."""
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if abs(nbytes) < 1000 or unit == "PB":
            return f"{nbytes:.0f} {unit}" if unit == "B" else f"{nbytes:.1f} {unit}"
        nbytes /= 1000
    raise AssertionError  # not reached


def estimate_run_memory(n: int, n_snapshots: int, *, keep_snapshots: bool = False,
                        damped: bool = False, samples: int = 0) -> int:
    """Bytes of memory one run of ``n`` balls and ``n_snapshots`` snapshots needs.

    Parameters
    ----------
    n : int
        Number of balls, >= 1.
    n_snapshots : int
        Number of snapshot times T, >= 0.
    keep_snapshots : bool
        Whether the snapshots stay in memory (``chainrun.solver.simulate`` without an
        ``on_snapshot`` observer): then add ``2 * T * N`` float64. The runner streams
        them to the run file, so it does not.
    damped : bool
        Whether the line dissipates (``RunSpec.damped``): its state is larger.
    samples : int
        Force samples the run's sensors take (``RunSpec.sensor_samples``: sample
        times by sensor balls).

    Returns
    -------
    int
        An estimate of the run's arrays, not counting the Python interpreter and the
        libraries (about 200 MB).
    """
    n = max(int(n), 1)
    t = max(int(n_snapshots), 0)
    window = min(n, max(WINDOW_MIN, 4 * math.isqrt(n)))
    total = (
        n * (STATE_BYTES_PER_BALL + OUTPUT_BYTES_PER_BALL
             + (DAMPED_BYTES_PER_BALL if damped else 0))
        + window * WINDOW_BYTES_PER_BALL * 3 // 2  # the old window is freed after growing
        + t * BYTES_PER_TIME
        + max(int(samples), 0) * BYTES_PER_SAMPLE
        + FIXED_BYTES
    )
    if keep_snapshots:
        total += 2 * 8 * t * n
    return int(total)


def estimate_file_size(n: int, n_snapshots: int, samples: int = 0) -> int:
    """Bytes of a run file before compression: ``T * N * 2 * 8`` for the snapshots,
    plus the per-ball results (4 arrays of N float64), the per-snapshot observables
    and the sensors' samples (two forces and their mean, 3 x 8 bytes each)."""
    n = max(int(n), 1)
    t = max(int(n_snapshots), 0)
    return 2 * 8 * t * n + 4 * 8 * n + 5 * 8 * t + 3 * 8 * max(int(samples), 0)


def memory_available() -> int | None:
    """Bytes of memory available to a new process now, or None if unknown.

    ``MemAvailable`` of ``/proc/meminfo`` (Linux 3.14+), else free physical pages
    (``os.sysconf``), else None.
    """
    try:
        with open(_MEMINFO, encoding="ascii") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    fields = line.split()
                    scale = 1024 if fields[2:3] == ["kB"] else 1
                    return int(fields[1]) * scale
    except (OSError, ValueError, IndexError):
        pass
    try:
        pages = os.sysconf("SC_AVPHYS_PAGES")
        page = os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, ValueError, OSError):
        return None
    if pages < 0 or page <= 0:
        return None
    return int(pages) * int(page)


def check_memory(n: int, n_snapshots: int, available: int | None = None, *,
                 runs_at_once: int = 1, damped: bool = False, samples: int = 0) -> int:
    """Refuse a run that would not fit in memory.

    Parameters
    ----------
    n, n_snapshots : int
        The run's number of balls and snapshot times.
    available : int, optional
        Bytes available; by default ``memory_available()``. When that is unknown,
        nothing is refused.
    runs_at_once : int
        Runs of this size computed at once on this machine (``--jobs``).
    damped : bool
        Whether the line dissipates (its state is larger).
    samples : int
        Force samples of the run's sensors.

    Returns
    -------
    int
        The estimate, in bytes, of one run.

    Raises
    ------
    ChainrunError
        One line with the estimate and the memory available.
    """
    need = estimate_run_memory(n, n_snapshots, damped=damped, samples=samples)
    if available is None:
        available = memory_available()
    together = need * max(int(runs_at_once), 1)
    if available is not None and together > available:
        what = f"a run of N = {n} balls with {n_snapshots} snapshots" + (
            f" and {samples} force samples (output.sensor_dt, output.sensor_end)"
            if samples else "")
        times = "" if runs_at_once <= 1 else f" ({runs_at_once} at once: {human_size(together)})"
        raise ChainrunError(
            f"{what} needs about {human_size(need)} of memory{times}, "
            f"but {human_size(available)} is available"
        )
    return need


def free_disk(folder) -> int | None:
    """Bytes free for an unprivileged user on the disk of ``folder``, or None if unknown.

    ``folder`` need not exist yet: its nearest existing parent is asked.
    """
    path = Path(folder).absolute()
    for candidate in (path, *path.parents):
        try:
            return shutil.disk_usage(candidate).free
        except FileNotFoundError:
            continue
        except OSError:
            return None
    return None


def check_disk(n: int, n_snapshots: int, folder, free: int | None = None, *,
               runs: int = 1) -> str | None:
    """A one-line warning if the run files could exceed the free disk space, else None.

    Parameters
    ----------
    n, n_snapshots : int
        The (largest) run's number of balls and snapshot times.
    folder : path
        Where the files go (it need not exist yet).
    free : int, optional
        Bytes free; by default ``free_disk(folder)``. When that is unknown, no warning.
    runs : int
        Number of such run files.
    """
    size = estimate_file_size(n, n_snapshots) * max(int(runs), 1)
    return _disk_warning(size, max(int(runs), 1), folder, free)


def _disk_warning(size: int, runs: int, folder, free: int | None) -> str | None:
    """A warning where the files may not fit on the disk, or are large enough that a
    user asking for them may not have meant it (``LARGE_OUTPUT``); else None."""
    if free is None:
        free = free_disk(folder)
    what = "the run file" if runs <= 1 else f"the {runs} run files"
    if free is not None and size > free:
        return (f"{what} may take up to {human_size(size)} before compression, "
                f"and {human_size(free)} is free in {folder}")
    if size > LARGE_OUTPUT:
        return (f"{what} may take up to {human_size(size)} before compression (mostly "
                f"snapshots: fewer output.times keep {'it' if runs <= 1 else 'them'} "
                "small)")
    return None


def check_runs(specs, folder, *, runs_at_once: int = 1, available: int | None = None,
               free: int | None = None) -> list[str]:
    """Check a sweep's runs against this machine before computing them.

    Refuses (``ChainrunError``) when the largest run, ``runs_at_once`` times over, would
    not fit in memory; returns the warnings for the disk (a list of at most one line).

    Parameters
    ----------
    specs : list of RunSpec
        The runs to compute (``n``, ``times``, ``damped`` and ``sensor_samples`` are
        used).
    folder : path
        The output folder.
    runs_at_once : int
        Runs computed at once on this machine.
    """
    specs = list(specs)
    if not specs:
        return []
    sizes = [(int(s.n), len(s.times), s.damped, s.sensor_samples) for s in specs]
    n, t, damped, samples = max(sizes, key=lambda run: estimate_run_memory(
        run[0], run[1], damped=run[2], samples=run[3]))
    check_memory(n, t, available=available, damped=damped, samples=samples,
                 runs_at_once=min(max(int(runs_at_once), 1), len(specs)))
    total = sum(estimate_file_size(n, t, samples) for n, t, _, samples in sizes)
    warning = _disk_warning(total, len(specs), folder, free)
    return [] if warning is None else [warning]
