"""Peer: heyoka's Taylor integrator, one on/off parameter and one event per contact.

This module owns the benchmark's heyoka formulation (``pip install heyoka``, in the
``bench`` extra; without it ``solve`` raises ``PeerUnavailable``). heyoka integrates
a fixed symbolic system, so the clamp ``(c_j)_+^alpha`` is expressed with one runtime
parameter ``p_j`` in {0, 1} per contact (contact j joins balls j and j+1, 0-based)::

    f_j = p_j * (p_j c_j + 1 - p_j)^alpha        (f_j = p_j c_j for alpha = 1)

(the base is 1 while the contact is off, so the power's Taylor recurrence never sees
a negative or zero base), and one terminal event per contact switches it::

    g_j = c_j - eps = 0

An off contact switches on where its compression rises through ``eps``, an on contact
off where it falls through ``eps``; the callback flips ``p_j`` only for a crossing in
the expected direction. Every contact starts off. The whole system is compiled in
compact mode (one loop over the contacts instead of unrolled code), and the
compilation is timed separately.

Why ``eps``: ``c^alpha`` is not analytic at c = 0 for non-integer alpha, and the Taylor
recurrence of a power divides by its base, so an on contact must never reach c = 0
(at t = 0 every contact has c = 0, and behind a Hertz wave contacts linger at
compressions of 1e-16, rounding level, where they would). For alpha = 1 the power is
not needed, but event functions that are exactly 0 over the whole line ahead of the
wave (``g_j = c_j``) stall heyoka at t = 0 and then make its root search very slow
(N = 1000: 147 s instead of 0.7 s). So the force law is ``c^alpha`` for ``c >= eps`` and
0 below, with ``eps = 1e-10`` for alpha > 1 and ``1e-14`` for alpha = 1: it differs from
the true law by at most ``eps^alpha``, 1e-15 and 1e-14, below the other errors.

References
----------
F. Biscani and D. Izzo, Revisiting high-order Taylor methods for astrodynamics and
celestial mechanics, MNRAS 504 (2021) 2614-2628 (heyoka).
"""

from __future__ import annotations

import time

import numpy as np

from benchmarks.peers import PeerResult, PeerUnavailable

__all__ = ["available", "default_eps", "solve", "version", "EPS", "EPS_LINEAR"]

#: Compression below which a contact carries no force, for alpha > 1 and alpha = 1.
EPS = 1e-10
EPS_LINEAR = 1e-14


def default_eps(alpha: float) -> float:
    """``EPS_LINEAR`` for alpha = 1, else ``EPS``."""
    return EPS_LINEAR if float(alpha) == 1.0 else EPS


def _import():
    try:
        import heyoka
    except ImportError as exc:
        raise PeerUnavailable(
            f"heyoka is not installed ({exc}); `pip install 'chainrun[bench]'` adds it"
        ) from None
    return heyoka


def available() -> tuple[bool, str]:
    """Whether heyoka can be imported here, and the reason if not."""
    try:
        _import()
    except PeerUnavailable as exc:
        return False, str(exc)
    return True, ""


def version() -> str | None:
    try:
        return _import().__version__
    except PeerUnavailable:
        return None


class _Switch:
    """Terminal-event callback of contact j: flips p_j on a crossing in its direction.

    heyoka deep-copies callbacks; this one shares its counter, so copying returns
    itself.
    """

    def __init__(self, j: int, counter: list):
        self.j = j
        self.counter = counter

    def __call__(self, ta, d_sgn) -> bool:
        pars = ta.pars
        on = pars[self.j] != 0.0
        if (on and d_sgn < 0) or (not on and d_sgn > 0):
            pars[self.j] = 0.0 if on else 1.0
            self.counter[0] += 1
        return True

    def __deepcopy__(self, memo):
        return self


def build(n: int, alpha: float, *, eps: float | None = None, tol: float | None = None,
          cached: bool = False):
    """The compiled integrator for ``n`` balls (state and parameters to be set).

    heyoka keeps compiled code in memory and on disk (``~/.cache/heyoka``); unless
    ``cached``, both are bypassed so that ``compile_time`` is a first compilation.

    Returns
    -------
    ta : heyoka.taylor_adaptive
    counter : list of one int
        Incremented by each contact switch.
    compile_time : float
        Wall time of building and compiling the integrator, in seconds.
    """
    hy = _import()
    # Terminal events whose crossing rate is zero get a zero cooldown, with a warning
    # each (millions here); the callback's direction test makes them harmless.
    hy.set_logger_level_error()
    alpha = float(alpha)
    eps = default_eps(alpha) if eps is None else float(eps)
    if not cached:
        hy.llvm_state.clear_memcache()
        hy.llvm_state.set_diskcache_enabled(False)
    t0 = time.perf_counter()
    xs = hy.make_vars(*[f"x{i}" for i in range(n)])
    vs = hy.make_vars(*[f"v{i}" for i in range(n)])
    if n == 1:
        xs, vs = [xs], [vs]
    forces = []
    events = []
    counter = [0]
    for j in range(n - 1):
        p = hy.par[j]
        c = xs[j] - xs[j + 1]
        if alpha == 1.0:
            forces.append(p * c)
        else:
            forces.append(p * (p * c + (1.0 - p)) ** alpha)
        events.append(hy.t_event(c - eps, callback=_Switch(j, counter),
                                 direction=hy.event_direction.any))
    acc = []
    for i in range(n):
        terms = []
        if i > 0:
            terms.append(forces[i - 1])
        if i < n - 1:
            terms.append(-forces[i])
        acc.append(hy.sum(terms) if terms else hy.expression(0.0))
    sys = [(xs[i], vs[i]) for i in range(n)] + [(vs[i], acc[i]) for i in range(n)]
    kwargs = {} if tol is None else {"tol": tol}
    ta = hy.taylor_adaptive(sys, np.zeros(2 * n), pars=np.zeros(max(n - 1, 1)),
                            t_events=events, compact_mode=True, **kwargs)
    return ta, counter, time.perf_counter() - t0


def solve(n: int, k: int, alpha: float, t_stop: float, *, eps: float | None = None,
          tol: float | None = None, cached: bool = False) -> PeerResult:
    """Integrate a line of ``n`` balls, the first ``k`` at velocity 1, to ``t_stop``.

    Parameters
    ----------
    n, k : int
        Balls, and impacting balls (1 <= k <= n, n >= 2).
    alpha : float
        Contact exponent, >= 1.
    t_stop : float
        End time.
    eps : float, optional
        Compression below which a contact carries no force (see the module's
        docstring); by default ``default_eps(alpha)``.
    tol : float, optional
        heyoka's tolerance; by default its own (machine epsilon).
    cached : bool
        Let heyoka reuse compiled code from its memory and disk caches (by default
        they are bypassed, and ``compile_time`` is a first compilation).

    Returns
    -------
    PeerResult
        ``compile_time`` is the build and JIT compilation of the system, which
        depends on N; ``solve_time`` the propagation alone.
    """
    hy = _import()
    alpha = float(alpha)
    eps = default_eps(alpha) if eps is None else float(eps)
    ta, counter, compile_time = build(n, alpha, eps=eps, tol=tol, cached=cached)
    state = np.zeros(2 * n)
    state[n:n + k] = 1.0
    ta.state[:] = state
    ta.time = 0.0
    t0 = time.perf_counter()
    outcome = ta.propagate_until(float(t_stop))
    solve_time = time.perf_counter() - t0
    if outcome[0] != hy.taylor_outcome.time_limit:
        raise RuntimeError(f"heyoka stopped at t = {ta.time}: {outcome[0]}")
    return PeerResult(
        tool="heyoka", settings=f"Taylor tol={ta.tol:.1e} order={ta.order} eps={eps:g}",
        t_end=float(ta.time), final_position=ta.state[:n].copy(),
        final_velocity=ta.state[n:].copy(), steps=int(outcome[3]), events=counter[0],
        solve_time=solve_time, compile_time=compile_time,
    )
