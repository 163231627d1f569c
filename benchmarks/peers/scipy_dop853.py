"""Peer: scipy's DOP853 with a fixed active contact set between events.

This module owns the benchmark's scipy baseline, written as a careful researcher
would write it with scipy alone (it shares no code with ``chainrun`` nor with the
test suite's ``tests/reference.py``):

* Between events the set of *active* contacts is fixed and the right-hand side is
  smooth: an active contact j carries ``sign(c_j) |c_j|^alpha``, the smooth
  continuation of ``(c_j)_+^alpha`` to slightly negative compressions; an inactive
  one carries nothing. The right-hand side is vectorised numpy over the whole line.
* After each accepted step, sign changes of the compressions between the step's ends
  are found for all contacts at once (as ``solve_ivp`` does for its events): an
  active contact going + to - is an opening, an inactive one going - to + a closing.
  Each candidate is located on the step's dense output (``brentq``); crossings
  slower than ``floor`` are rounding noise (compressions of 1e-70 ahead of a Hertz
  wave) and are ignored.
* The segment is then integrated again from the step's start exactly to the
  earliest event (no step crosses the non-smooth point), the contact is switched
  from the event (not from the sign of ``c_j``, which is +-1e-17 there), contacts
  that crossed at the same instant to rounding are switched too, and DOP853 restarts
  with the new set. With no active contact the balls fly freely up to the next
  collision, computed in closed form.

Initially every contact touches at zero compression and all are active (the line is
one cluster). The run ends at ``t_stop``.

References
----------
E. Hairer, S. P. Norsett, G. Wanner, *Solving Ordinary Differential Equations I*,
2nd ed., Springer (1993), section II.10 (DOP853 and its dense output).
"""

from __future__ import annotations

import time

import numpy as np
from scipy.integrate import DOP853
from scipy.optimize import brentq

from benchmarks.peers import PeerResult

__all__ = ["solve", "RTOL", "ATOL", "FLOOR"]

#: Default accuracy of the DOP853 steps.
RTOL = 1e-12
ATOL = 1e-14
#: Relative speeds below this are rounding noise: not openings, not closings.
FLOOR = 1e-12


def _make_rhs(n: int, alpha: float, active: np.ndarray):
    """Right-hand side for a fixed active set; y = (x (N), v (N))."""
    mask = active.astype(float)
    power = alpha - 1.0
    out = np.empty(2 * n)

    def rhs(t, y):
        c = y[: n - 1] - y[1:n]
        if power == 0.0:
            f = c * mask
        else:
            f = c * np.abs(c) ** power * mask
        out[:n] = y[n:]
        a = out[n:]
        a[0] = -f[0]
        a[1:-1] = f[:-1] - f[1:]
        a[-1] = f[-1]
        return out.copy()

    return rhs


def _finish(solver) -> int:
    """Step ``solver`` to its t_bound; the number of steps taken."""
    steps = 0
    while solver.status == "running":
        message = solver.step()
        steps += 1
        if solver.status == "failed":
            raise RuntimeError(f"DOP853 failed at t = {solver.t}: {message}")
    return steps


def _locate(dense, n: int, j: int, t0: float, t1: float) -> float:
    """Root of the compression of contact j on the dense output, in [t0, t1]."""

    def c(t):
        y = dense(t)
        return y[j] - y[j + 1]

    c0, c1 = c(t0), c(t1)
    if c0 == 0.0 or c1 == 0.0 or (c0 > 0) != (c1 > 0):
        return brentq(c, t0, t1, xtol=1e-15, maxiter=200)
    return t1                     # the interpolant misses the step's end by rounding


def solve(n: int, k: int, alpha: float, t_stop: float, *, rtol: float = RTOL,
          atol: float = ATOL, floor: float = FLOOR) -> PeerResult:
    """Integrate a line of ``n`` balls, the first ``k`` at velocity 1, to ``t_stop``.

    Parameters
    ----------
    n, k : int
        Balls, and impacting balls (1 <= k <= n, n >= 2).
    alpha : float
        Contact exponent, >= 1.
    t_stop : float
        End time.
    rtol, atol : float
        Tolerances of the DOP853 steps (positions and velocities alike).
    floor : float
        Crossings with a relative speed below this are ignored.

    Returns
    -------
    PeerResult
    """
    wall0 = time.perf_counter()
    alpha = float(alpha)
    m = n - 1
    y = np.zeros(2 * n)
    y[n:n + k] = 1.0
    t = 0.0
    active = np.full(m, k < n)
    steps = events = 0
    h_next = None

    def switch_consistent(yy: np.ndarray) -> int:
        """Switch contacts that crossed at the restart instant, to rounding."""
        c = yy[:m] - yy[1:n]
        r = yy[n:n + m] - yy[n + 1:]
        opened = active & (c <= 0) & (r < -floor)
        closed = ~active & (c >= 0) & (r > floor)
        active[opened] = False
        active[closed] = True
        return int(opened.sum() + closed.sum())

    while t < t_stop:
        if not active.any():
            # Free flight: the next collision in closed form.
            c = y[:m] - y[1:n]
            r = y[n:n + m] - y[n + 1:]
            approaching = r > floor
            dt = t_stop - t
            j = -1
            if approaching.any():
                tc = np.where(approaching, np.maximum(-c, 0.0) / np.where(approaching, r, 1.0),
                              np.inf)
                j = int(np.argmin(tc))
                if tc[j] < dt:
                    dt = tc[j]
                else:
                    j = -1
            y[:n] += y[n:] * dt
            t += dt
            if j >= 0:
                y[j + 1] = y[j]          # exact touch
                active[j] = True
                events += 1 + switch_consistent(y)
            continue

        rhs = _make_rhs(n, alpha, active)
        solver = DOP853(rhs, t, y, t_stop, rtol=rtol, atol=atol,
                        first_step=None if h_next is None else min(h_next, t_stop - t))
        found = None
        while solver.status == "running":
            t0, y0 = solver.t, solver.y.copy()
            message = solver.step()
            steps += 1
            if solver.status == "failed":
                raise RuntimeError(f"DOP853 failed at t = {t0}: {message}")
            y1 = solver.y
            c0 = y0[:m] - y0[1:n]
            c1 = y1[:m] - y1[1:n]
            crossing = np.flatnonzero((active & (c0 > 0) & (c1 <= 0))
                                      | (~active & (c0 < 0) & (c1 >= 0)))
            if crossing.size == 0:
                continue
            dense = solver.dense_output()
            best = None
            for j in crossing:
                tj = _locate(dense, n, j, t0, solver.t)
                yj = dense(tj)
                rate = yj[n + j] - yj[n + j + 1]
                want = -1.0 if active[j] else 1.0
                if want * rate > floor and (best is None or tj < best[0]):
                    best = (tj, j)
            if best is not None:
                found = (best[0], best[1], t0, y0)
                break
        h_next = solver.h_abs if solver.h_abs else h_next

        if found is None:                  # reached t_stop
            t, y = solver.t, solver.y.copy()
            break
        te, j, t0, y0 = found
        # Integrate the segment again, exactly to the event: no step crosses it.
        if te > t0:
            again = DOP853(rhs, t0, y0, te, rtol=rtol, atol=atol, first_step=te - t0)
            steps += _finish(again)
            y = again.y.copy()
        else:
            y = y0
        t = te
        active[j] = not active[j]
        events += 1 + switch_consistent(y)

    if t < t_stop:
        y[:n] += y[n:] * (t_stop - t)
    return PeerResult(
        tool="scipy", settings=f"DOP853 rtol={rtol:g} atol={atol:g}", t_end=float(t_stop),
        final_position=y[:n].copy(), final_velocity=y[n:].copy(), steps=steps,
        events=events, solve_time=time.perf_counter() - wall0,
    )
