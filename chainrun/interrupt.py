"""Interrupts that are not lost.

Python's own SIGINT handler raises ``KeyboardInterrupt`` wherever the interpreter is,
and where that is a callback whose exceptions are ignored (h5py frees its objects in
weak-reference callbacks while a run file is written), the interrupt is printed as
"Exception ignored" and the run goes on. The command line's handler (``install``) also
remembers the signal, and the runs' hooks (each snapshot written, each progress report)
raise it again there (``check``): a run stops at its next snapshot however the first
raise fared.
"""

from __future__ import annotations

import signal

__all__ = ["check", "clear", "handler", "install"]

_pending = False


def handler(signum, frame):
    """Remember the interrupt, and raise it now."""
    global _pending
    _pending = True
    raise KeyboardInterrupt


def install() -> None:
    """Handle SIGINT, SIGTERM and SIGHUP with ``handler`` (a terminated run, by a job's
    time limit, `timeout` or a closed terminal, is an interrupted one), where Python's
    or the system's default handles them now: a signal the process was started to
    ignore (a background job's SIGINT) stays ignored."""
    for name in ("SIGINT", "SIGTERM", "SIGHUP"):
        number = getattr(signal, name, None)
        if number is not None and signal.getsignal(number) in (
                signal.SIG_DFL, signal.default_int_handler):
            signal.signal(number, handler)


def check() -> None:
    """Raise ``KeyboardInterrupt`` if an interrupt came and was not acted on."""
    global _pending
    if _pending:
        _pending = False
        raise KeyboardInterrupt


def clear() -> None:
    """Forget an interrupt that was acted on."""
    global _pending
    _pending = False
