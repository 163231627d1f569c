"""A slow, independent reference solver for short lines of balls (test-only).

This module owns the test suite's second opinion on the dynamics. It shares no code
with ``chainrun.solver``: it integrates, in paper units,

    x_n'' = (x_{n-1} - x_n)_+^alpha - (x_n - x_{n+1})_+^alpha,
    x_n(0) = 0,  x_n'(0) = 1 for n <= K, 0 otherwise,

with scipy's order-8 Dormand-Prince pair (``scipy.integrate.DOP853``, the method behind
``solve_ivp(method="DOP853")``), event by event. (chainrun's kernels borrow the same
DOP853 coefficients; the stepping, event logic and bookkeeping here are separate, and
this solver is checked on its own against closed forms, Table 1 and exact symmetries
in ``tests/test_reference_solver.py``.)

Method
------
* A set of *active* contacts is kept. Between changes of the set the right-hand side
  is smooth: an active contact j carries the force ``sign(c_j) |c_j|^alpha`` (``c_j``
  for alpha = 1), the smooth continuation of ``(c_j)_+^alpha`` to slightly negative
  compression; an inactive contact carries nothing.
* After each accepted step the compression of every contact is sampled on the step's
  dense interpolant (``SAMPLES`` points per step, so an opening followed by a
  re-closing inside one step is still seen). An *opening* is a sign change + to - of
  an active contact's compression; a *closing* is a change - to + of an inactive one.
  Exact zeros (ahead of the wave the compressions underflow to 0) carry no sign, and a
  crossing counts only if the contact opens (closes) faster than ``FLOOR``: rounding
  noise in compressions of 1e-70 ahead of a Hertz wave is not an opening.
* The earliest root is bracketed on the interpolant (``brentq``), then refined by
  Newton's method on the *integrated* flow: the crossing step is integrated again with
  ``solve_ivp`` from its start exactly to the candidate time, so that no step crosses
  the non-smooth point (for non-integer alpha the force is only finitely often
  differentiable at c = 0, and a step across it loses the method's order), and the
  candidate is corrected by ``-c_j / c_j'``. The contact's new state is set from the
  event, not from the sign of ``c_j`` (which is +-1e-17 there). At every restart the
  active set is checked for consistency: a contact that crossed at the same instant
  (to rounding) is switched too.
* Initially all contacts touch at zero compression; all are active from t = 0 (the
  whole line is one cluster; fine for the short lines this is meant for). For K = N
  nothing ever happens. (For its own tests, ``initial=(x0, v0)`` starts from any
  state instead; then a contact is active if compressed, or touching and closing.)
* When no contact is active the balls fly freely and the next collision is computed in
  closed form. The run ends in the *terminal state*: no active contact and no pair of
  neighbours approaching faster than ``FLOOR`` (slower approaches are rounding noise
  and are ignored), or at ``t_max``.

Accuracy
--------
Meant for N <= 8, any 1 <= K <= N, alpha in [1, 3]. Measured over N = 2..8, every
K, alpha in {1, 1.25, 1.5, 2, 2.5, 3} (203 runs), the final velocities at the default
``rtol = 1e-13``, ``atol = 1e-15`` differ from those at rtol = 2.2e-14 (scipy's floor
for DOP853) by at most 3.7e-12, and those at rtol = 1e-12 by at most 1.2e-10 (both
worst at alpha = 2.5); so at the default they are trusted to 1e-10. Momentum is
conserved to 3e-15 and energy to 3e-12 (relative). The two-ball linear case matches
its closed form to 1e-14. It is slow (pure Python, ~0.1 s per run at N = 8, growing
with the number of steps) and must not be used on long lines.

References
----------
E. Hairer, S. P. Norsett, G. Wanner, *Solving Ordinary Differential Equations I*,
2nd ed., Springer (1993), section II.10 (DOP853 and its dense output).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import DOP853, solve_ivp
from scipy.optimize import brentq

__all__ = ["RefSolution", "reference_solve", "REF_RTOL", "REF_ATOL", "FLOOR", "OPEN", "CLOSE"]

#: Default accuracy of the reference integration.
REF_RTOL = 1e-13
REF_ATOL = 1e-15
#: Relative speeds below this are rounding noise: not collisions, not openings.
FLOOR = 1e-12
#: Dense-output samples per accepted step used to look for sign changes.
SAMPLES = 8
#: Event kinds, with the values of ``chainrun.solver.EventKind``.
OPEN = -1
CLOSE = 1


@dataclass(frozen=True)
class RefSolution:
    """Result of one reference run.

    Attributes
    ----------
    n, k : int
    alpha : float
    terminal : bool
        Whether the terminal state was reached before ``t_max``.
    end_time : float
        Time of the last event (the terminal time), or ``t_max``.
    final_position, final_velocity : ndarray, shape (N,)
        State at ``end_time``.
    event_time : ndarray, shape (E,)
    event_contact : ndarray of int64, shape (E,)
        Contact j joins balls j and j+1 (0-based).
    event_kind : ndarray of int8, shape (E,)
        ``OPEN`` (-1) or ``CLOSE`` (+1).
    event_compression : ndarray, shape (E,)
        The contact's compression at the event (zero to rounding).
    separation_time, separation_velocity : ndarray, shape (N,)
        Time and velocity at which each ball last lost its last contact; NaN if it
        never did.
    steps : int
        Accepted integration steps (first pass).
    """

    n: int
    k: int
    alpha: float
    terminal: bool
    end_time: float
    final_position: np.ndarray
    final_velocity: np.ndarray
    event_time: np.ndarray
    event_contact: np.ndarray
    event_kind: np.ndarray
    event_compression: np.ndarray
    separation_time: np.ndarray
    separation_velocity: np.ndarray
    steps: int


def _make_rhs(n: int, alpha: float, active: np.ndarray):
    """Right-hand side for a fixed active set; y = (x (N), v (N))."""
    mask = active.astype(float)
    linear = alpha == 1.0

    def rhs(t, y):
        x = y[:n]
        c = x[:-1] - x[1:]
        if linear:
            f = c * mask
        else:
            f = np.sign(c) * np.abs(c) ** alpha * mask
        a = np.zeros(n)
        a[1:] += f
        a[:-1] -= f
        return np.concatenate((y[n:], a))

    return rhs


def _integrate_to(rhs, t0, y0, t1, rtol, atol):
    """State at t1 from (t0, y0), with a step ending exactly at t1."""
    if t1 <= t0:
        return y0.copy()
    sol = solve_ivp(rhs, (t0, t1), y0, method="DOP853", rtol=rtol, atol=atol,
                    first_step=t1 - t0)
    if sol.status != 0:
        raise RuntimeError(f"reference integration failed at t={t0}: {sol.message}")
    return sol.y[:, -1]


def reference_solve(n: int, k: int, alpha: float, *, rtol: float = REF_RTOL,
                    atol: float = REF_ATOL, t_max: float = 1e8,
                    max_events: int = 100_000, initial=None) -> RefSolution:
    """Run a line of ``n`` balls, the first ``k`` struck at velocity 1, to its terminal state.

    Parameters
    ----------
    n : int
        Number of balls, >= 1 (meant for n <= 8).
    k : int
        Number of impacting balls, 1 <= k <= n.
    alpha : float
        Contact exponent, >= 1.
    rtol, atol : float
        Tolerances of the DOP853 steps (on positions and velocities alike).
    t_max : float
        Give up (``terminal=False``) past this time.
    max_events : int
        Safety limit on the number of contact events.
    initial : (ndarray, ndarray), optional
        ``(x0, v0)``, each of shape (N,), to start from another state (``k`` is then
        only recorded). A contact is active initially if compressed, or touching
        and closing faster than ``FLOOR``.

    Returns
    -------
    RefSolution
    """
    if n < 1 or not 1 <= k <= n:
        raise ValueError(f"need n >= 1 and 1 <= k <= n, got n={n}, k={k}")
    alpha = float(alpha)
    t = 0.0
    m = n - 1
    if initial is None:
        x = np.zeros(n)
        v = np.zeros(n)
        v[:k] = 1.0
        active = np.full(m, k < n)    # one cluster touching at zero compression
    else:
        x = np.array(initial[0], dtype=float)
        v = np.array(initial[1], dtype=float)
        c = x[:-1] - x[1:]
        active = (c > 0) | ((c == 0) & (v[:-1] - v[1:] > FLOOR))
    events: list[tuple[float, int, int]] = []
    sep_t = np.full(n, np.nan)
    sep_v = np.full(n, np.nan)
    steps = 0

    def switch(j: int, kind: int, tj: float, pos: np.ndarray, vel: np.ndarray) -> None:
        events.append((tj, j, kind, pos[j] - pos[j + 1]))
        active[j] = kind == CLOSE
        if kind == OPEN:
            for b in (j, j + 1):
                left = b > 0 and active[b - 1]
                right = b < m and active[b]
                if not (left or right):
                    sep_t[b] = tj
                    sep_v[b] = vel[b]

    def restart_consistency(tj: float, xx: np.ndarray, vv: np.ndarray) -> None:
        # Contacts that crossed at the same instant, to rounding.
        c = xx[:-1] - xx[1:]
        r = vv[:-1] - vv[1:]
        for j in range(m):
            if active[j] and c[j] <= 0 and r[j] < -FLOOR:
                switch(j, OPEN, tj, xx, vv)
            elif not active[j] and c[j] >= 0 and r[j] > FLOOR:
                switch(j, CLOSE, tj, xx, vv)

    terminal = False
    while len(events) < max_events:
        if not active.any():
            # Free flight: next collision in closed form.
            c = x[:-1] - x[1:]
            r = v[:-1] - v[1:]
            best, jbest = np.inf, -1
            for j in range(m):
                if r[j] > FLOOR:
                    tc = max(-c[j], 0.0) / r[j]
                    if tc < best:
                        best, jbest = tc, j
            if jbest < 0:
                terminal = True
                break
            if t + best > t_max:
                break
            x = x + v * best
            t = t + best
            x[jbest + 1] = x[jbest]   # exact touch
            switch(jbest, CLOSE, t, x, v)
            restart_consistency(t, x, v)
            continue

        # One smooth segment with a fixed active set.
        rhs = _make_rhs(n, alpha, active)
        y = np.concatenate((x, v))
        solver = DOP853(rhs, t, y, t_max, rtol=rtol, atol=atol)
        c0 = x[:-1] - x[1:]
        last_sign = np.sign(c0)
        found = None
        while solver.status == "running":
            t_old, y_old = solver.t, solver.y.copy()
            msg = solver.step()
            if solver.status == "failed":
                raise RuntimeError(f"reference integration failed at t={t_old}: {msg}")
            steps += 1
            dense = solver.dense_output()
            ts = np.linspace(t_old, solver.t, SAMPLES + 1)[1:]
            ys = dense(ts)
            ys[:, -1] = solver.y
            cs = ys[:n - 1] - ys[1:n]                 # shape (m, SAMPLES)
            candidates = []
            for j in range(m):
                s_prev = last_sign[j]
                t_prev = t_old
                want = -1.0 if active[j] else 1.0     # sign after the crossing
                for i in range(SAMPLES):
                    s = np.sign(cs[j, i])
                    if s == want and s_prev != want:
                        # c(t_prev) has sign s_prev or is exactly 0.
                        tr = brentq(lambda tt: dense(tt)[j] - dense(tt)[j + 1],
                                    t_prev, ts[i], xtol=1e-16, rtol=1e-15)
                        yr = dense(tr)
                        rate = yr[n + j] - yr[n + j + 1]
                        if want * rate > FLOOR:
                            candidates.append((tr, j))
                            break
                    if s != 0:
                        s_prev = s
                    t_prev = ts[i]
                last_sign[j] = s_prev
            if candidates:
                tr, j = min(candidates)
                found = (tr, j, t_old, y_old)
                break

        if found is None:
            t = solver.t
            x, v = solver.y[:n].copy(), solver.y[n:].copy()
            break                                        # reached t_max

        tr, j, t_old, y_old = found
        # Newton on the integrated flow: no step crosses the non-smooth point.
        yr = _integrate_to(rhs, t_old, y_old, tr, rtol, atol)
        for _ in range(8):
            dt = -(yr[j] - yr[j + 1]) / (yr[n + j] - yr[n + j + 1])
            if abs(dt) <= 4e-16 * max(1.0, tr):
                break
            tr = tr + dt
            yr = _integrate_to(rhs, t_old, y_old, tr, rtol, atol)
        t = tr
        x, v = yr[:n].copy(), yr[n:].copy()
        switch(j, CLOSE if not active[j] else OPEN, t, x, v)
        restart_consistency(t, x, v)

    return RefSolution(
        n=n, k=k, alpha=alpha, terminal=terminal, end_time=t,
        final_position=x, final_velocity=v,
        event_time=np.array([e[0] for e in events], dtype=float),
        event_contact=np.array([e[1] for e in events], dtype=np.int64),
        event_kind=np.array([e[2] for e in events], dtype=np.int8),
        event_compression=np.array([e[3] for e in events], dtype=float),
        separation_time=sep_t, separation_velocity=sep_v, steps=steps,
    )
