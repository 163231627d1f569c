"""Atomic writes: every file chainrun makes appears whole or not at all.

A file is written under a temporary name beside its target, ``.<name>.partial-<pid>``,
flushed to disk and renamed over the target, and the folder is flushed too. A reader
never sees a half-written file; a writer killed midway leaves only a temporary file,
which nothing reads (``leftovers`` finds them) and the next complete write replaces.
The store (HDF5 files) and the figures use it.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Callable

_PARTIAL = ".partial-"


def temp_name(path: Path, keep_suffix: bool = False) -> Path:
    """The temporary name this process writes ``path`` under (ending in ``path``'s
    suffix too with ``keep_suffix``, for writers that choose a format by it)."""
    end = path.suffix if keep_suffix else ""
    return path.with_name(f".{path.name}{_PARTIAL}{os.getpid()}{end}")


def leftovers(folder: Path, names) -> list[Path]:
    """Temporary files of any process for the files ``names`` in ``folder``."""
    prefixes = tuple(f".{name}{_PARTIAL}" for name in names)
    if not prefixes or not folder.is_dir():
        return []
    return sorted(p for p in folder.iterdir() if p.name.startswith(prefixes))


def fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def fsync_dir(directory: Path) -> None:
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:  # not possible on every platform; the rename is still atomic
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def put_in_place(temp: Path, path: Path) -> None:
    """Flush the complete ``temp`` to disk and rename it over ``path`` (OSError on failure)."""
    fsync(temp)
    os.replace(temp, path)
    fsync_dir(path.parent)


def write(path: Path, write_to: Callable[[Path], object], *, keep_suffix: bool = False) -> None:
    """Write ``path`` atomically: ``write_to(temp)`` writes the content under a temporary
    name (see ``temp_name``), which is then put in place; on any error the temporary
    file is removed."""
    temp = temp_name(path, keep_suffix)
    try:
        write_to(temp)
        put_in_place(temp, path)
    finally:
        if temp.exists():
            temp.unlink()
