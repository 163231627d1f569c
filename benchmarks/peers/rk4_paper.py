"""Peer: the paper's own method, fixed-step RK4 landing on contact openings (numba).

This module owns the benchmark's version of the method of Hinch & Saint-Jean,
section 2: the classical fourth-order Runge-Kutta method with a fixed step ``dt`` on
the whole line, with the clamped force ``(c_j)_+^alpha`` throughout. "If a particle
was going to lose contact during the next time-step, then the size of the time-step
was adjusted so the separation occurred exactly at the end of the time-step, the
appropriate size of the time-step being estimated to second order from a knowledge
of x_n, x_n' and x_n'' at the beginning of the time-step": for every compressed
contact the opening time is predicted as the smallest positive root of
``c + c' s + c'' s^2 / 2`` and the step is shortened to the earliest one. Closings are
not treated (the paper does not), and the prediction is only second order, so the
force's kink still costs accuracy: about 1e-7 in the velocities at dt = 0.02 for
alpha = 3/2. The paper's other trick (integrating only the moving balls) is left out:
this integrates the whole line, so the cost grows like N times the run time.

References
----------
E. J. Hinch and S. Saint-Jean, The fragmentation of a line of balls by an impact,
Proc. R. Soc. Lond. A 455 (1999) 3201-3220, section 2.
"""

from __future__ import annotations

import math
import time

import numba as nb
import numpy as np

from benchmarks.peers import PeerResult

__all__ = ["solve", "DT"]

#: Default step, as in the issue's measurement of this method.
DT = 0.02
#: Predicted openings closer than this fraction of ``dt`` are not landed on (the
#: step is already at the opening to the prediction's accuracy).
MIN_FRACTION = 1e-6


@nb.njit(cache=True)
def _accel(x, alpha, mode, a):
    """a = clamped contact forces on each ball; mode 0 linear, 1 Hertz, 2 any alpha."""
    n = x.shape[0]
    for i in range(n):
        a[i] = 0.0
    for j in range(n - 1):
        c = x[j] - x[j + 1]
        if c > 0.0:
            if mode == 0:
                f = c
            elif mode == 1:
                f = c * math.sqrt(c)
            else:
                f = c ** alpha
            a[j] -= f
            a[j + 1] += f


@nb.njit(cache=True)
def _opening_time(c, cd, cdd, dt):
    """Smallest s in (0, dt] with c + cd s + cdd s^2 / 2 = 0, or inf (c > 0)."""
    half = 0.5 * cdd
    best = math.inf
    if half == 0.0:
        if cd < 0.0:
            best = -c / cd
    else:
        disc = cd * cd - 4.0 * half * c
        if disc >= 0.0:
            sq = math.sqrt(disc)
            # numerically stable pair of roots
            q = -0.5 * (cd + math.copysign(sq, cd))
            for s in (q / half, c / q if q != 0.0 else math.inf):
                if 0.0 < s < best:
                    best = s
    return best if best <= dt else math.inf


@nb.njit(cache=True)
def _run(x, v, alpha, mode, dt, t_stop, min_fraction):
    """Integrate in place to t_stop; returns (steps, landed openings)."""
    n = x.shape[0]
    a1 = np.empty(n)
    a2 = np.empty(n)
    a3 = np.empty(n)
    a4 = np.empty(n)
    xs = np.empty(n)
    v2 = np.empty(n)
    v3 = np.empty(n)
    v4 = np.empty(n)
    t = 0.0
    steps = 0
    landed = 0
    _accel(x, alpha, mode, a1)
    while t < t_stop:
        h = min(dt, t_stop - t)
        # predicted openings, to second order from x, x', x''
        shortened = False
        for j in range(n - 1):
            c = x[j] - x[j + 1]
            if c > 0.0:
                s = _opening_time(c, v[j] - v[j + 1], a1[j] - a1[j + 1], h)
                if min_fraction * dt < s < h:
                    h = s
                    shortened = True
        if shortened:
            landed += 1
        for i in range(n):
            xs[i] = x[i] + 0.5 * h * v[i]
            v2[i] = v[i] + 0.5 * h * a1[i]
        _accel(xs, alpha, mode, a2)
        for i in range(n):
            xs[i] = x[i] + 0.5 * h * v2[i]
            v3[i] = v[i] + 0.5 * h * a2[i]
        _accel(xs, alpha, mode, a3)
        for i in range(n):
            xs[i] = x[i] + h * v3[i]
            v4[i] = v[i] + h * a3[i]
        _accel(xs, alpha, mode, a4)
        for i in range(n):
            x[i] += h / 6.0 * (v[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i])
            v[i] += h / 6.0 * (a1[i] + 2.0 * a2[i] + 2.0 * a3[i] + a4[i])
        t = t_stop if h == t_stop - t else t + h
        steps += 1
        _accel(x, alpha, mode, a1)
    return steps, landed


def _mode(alpha: float) -> int:
    return 0 if alpha == 1.0 else (1 if alpha == 1.5 else 2)


def compile_kernels(alpha: float = 1.5) -> float:
    """Compile (or load from numba's cache) the kernels; the wall time it took."""
    t0 = time.perf_counter()
    x = np.zeros(3)
    v = np.array([1.0, 0.0, 0.0])
    _run(x, v, float(alpha), _mode(alpha), DT, 0.1, MIN_FRACTION)
    return time.perf_counter() - t0


def solve(n: int, k: int, alpha: float, t_stop: float, *, dt: float = DT) -> PeerResult:
    """Integrate a line of ``n`` balls, the first ``k`` at velocity 1, to ``t_stop``.

    Parameters
    ----------
    n, k : int
        Balls, and impacting balls (1 <= k <= n).
    alpha : float
        Contact exponent, >= 1.
    t_stop : float
        End time.
    dt : float
        The fixed step (shortened onto predicted openings and onto ``t_stop``).

    Returns
    -------
    PeerResult
        ``events`` counts the steps shortened onto a predicted opening; ``compile_time``
        is that of the first call in this process (JIT or numba cache load).
    """
    compile_time = compile_kernels(alpha)
    x = np.zeros(n)
    v = np.zeros(n)
    v[:k] = 1.0
    t0 = time.perf_counter()
    steps, landed = _run(x, v, float(alpha), _mode(alpha), float(dt), float(t_stop),
                         MIN_FRACTION)
    return PeerResult(
        tool="rk4", settings=f"RK4 dt={dt:g}", t_end=float(t_stop), final_position=x,
        final_velocity=v, steps=int(steps), events=int(landed),
        solve_time=time.perf_counter() - t0, compile_time=compile_time,
    )
