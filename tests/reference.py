"""A slow, independent reference solver for short lines of balls (test-only).

This module owns the test suite's second opinion on the dynamics. It shares no code
with ``chainrun.solver``: ``reference_line`` integrates a line of balls given as a
``chainrun.solver.model.Line``, or any record of the same arrays (read for its input
only). The paper's line, ``paper_line(n, k, alpha)``, is, in paper units,

    x_n'' = (x_{n-1} - x_n)_+^alpha - (x_n - x_{n+1})_+^alpha,
    x_n(0) = 0,  x_n'(0) = 1 for n <= K, 0 otherwise;

the method is described on it first, then for the general line (masses, stiffnesses,
exponents, gaps, positions, forces, walls, damping; section below). It steps with
scipy's order-8 Dormand-Prince pair (``scipy.integrate.DOP853``, the method behind
``solve_ivp(method="DOP853")``), event by event. (chainrun's kernels borrow the same
DOP853 coefficients; the stepping, event logic and bookkeeping here are separate, and
this solver is checked on its own against closed forms, Table 1 and exact symmetries
in ``tests/regression/test_reference_solver.py`` and
``tests/regression/test_reference_general.py``.) ``random_line`` draws the short
general lines the tests compare on.

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

The general line: ``reference_line``
-----------------------------------
``reference_line(line, t_max=..., times=...)`` integrates any
``chainrun.solver.model.Line`` (read for its input only), in any consistent units::

    m_i x_i'' = F_{i-1} - F_i + f_i,   F_j = kappa_j (delta_j)_+^alpha_j,
    delta_j = x_j - x_{j+1} - g_j,     delta_L = -x_1 - g_L,   delta_R = x_N - g_R,

with the same method as above, generalised:

* Each contact has its own stiffness, exponent and gap; a wall is a contact with a
  fixed "ball" at x = 0 beyond the line's end, so contact j (j = -1 .. N-1, the labels
  of chainrun's event log: -1 the left wall, N-1 the right wall) joins balls j and
  j + 1 of the line padded with the walls, and every compression is one expression.
* It integrates in units (mass, length, time) in which the line's speeds, masses and
  compressions are of order 1 (``reference_units``: the median mass, the contact of
  median stiffness, the largest initial speed, or for a line at rest the speed its
  loads give), so that ``FLOOR``, ``atol`` and ``rtol`` mean there what they mean
  in paper units; results are converted back. The paper's line is its own unit.
* Initially a contact is active if compressed, or touching (to 1e-13) and not
  parting: neither moving apart nor, touching at rest, pulled apart by the forces. When every active contact touches without load, without moving and
  without being pressed (none, a line moving as one body, or a line at rest ahead of
  a flying striker), the free flight takes over: positions are parabolas under the
  forces, and the next closing of an inactive contact is the earliest root of
  ``delta + r t + b t^2 / 2`` at which it closes faster than ``FLOOR``, from the
  cancellation-free pair of roots ``q / A``, ``C / q`` (``_closing_time``).
* The terminal state: the free flight would find no collision ever (no contact active
  under load, no pair approaching; a right wall counts as a ball at rest: v_N <= 0; a
  left one likewise: v_1 >= 0). A line with external forces or between two walls has
  none: it runs to ``t_max``, which it then requires.
* Snapshots at ``times`` are integrated exactly to each instant from the start of the
  step containing it (analytic in free flight; past the end of a terminal run, the
  free flight that follows it).

Damping. A contact (or wall) of ``line.damping`` eta > 0 and exponent beta pushes with
``F = max(0, kappa c^alpha + eta c^beta c')`` while in contact. Such a contact is
*engaged* (its force is the law's smooth continuation, ``sign(c)|c|^alpha`` below 0,
and its release is the law reaching 0 downward, an ``OPEN`` event at c > 0, located and
refined by Newton like the openings), then *loose* while c > 0: it carries no force,
and it watches both its law (turning positive again, a ``CLOSE`` at c > 0: a third body
pushed the pair together again before they parted) and its compression (crossing 0
downward: it parts, no event); once parted it closes, like any contact, where c
crosses 0 upward. ``dissipated`` integrates the power ``sum (F - kappa c_+^alpha) c'``
over the contacts as an extra component of the state (only for a damped line, so an
elastic one takes exactly its old steps): ``eta c^beta c'^2`` for an engaged contact,
``-kappa c^alpha c'`` for a loose one, whose stored energy is lost with it. Then
``line_energy + dissipated`` is the same at every instant. Checked in
``tests/regression/test_reference_damped.py``: two balls and a ball on a wall against the
damped oscillator's explicit solution (e to 1e-10, durations to 1e-10 relative; measured 3e-15
and 1.5e-13), the nonlinear laws against ``chainrun.solver.restitution``'s scaled
integration (1e-10), the energy balance on damped chains (1e-11; measured 1e-13), a
force resuming at c > 0, and eta -> 0.

Accuracy of the general line. Measured by ``PYTHONPATH=. python tests/reference.py``
(``_measure``) over 120 random lines of ``random_line`` (10 per family: masses to a
ratio 10, stiffnesses over a factor 10, exponents 1, 1.5, 2 mixed, gaps and overlaps,
heavy and light strikers, head-on strikers, walls on either side or both, gravity onto
a wall, initial positions; N = 2..6, up to 38 events): the final velocities at the
default tolerances differ from those at rtol = 2.3e-14 by at most 3.1e-12 (with
rtol = 1e-12 by up to 1.8e-10: a dozen collisions amplify the step errors), event
times by at most 2.5e-11 (1 + t): after a long free flight an event moves by the
velocity error times the flight time over the approach speed (2.3e-9 at t = 92, after
a flight of 66 time units), and final positions with it (2e-9); energy (minus the
forces' potential) is conserved to 1.3e-11 relative, momentum (without walls) to
1.1e-14. Against the closed forms, two balls of any masses and a
ball on a wall for alpha in 1..3 meet their final velocities to 7e-13 and their
contact durations to 2.5e-13 (relative). So its velocities are trusted to 1e-11 and
its event times to 1e-10 (1 + t). It takes 0.02 to 0.3 s per run.

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

__all__ = ["REF_RTOL", "REF_ATOL", "FLOOR", "OPEN", "CLOSE", "PaperLine", "paper_line",
           "RefLineSolution", "reference_line", "reference_units", "line_energy",
           "random_line", "FAMILIES"]

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
class PaperLine:
    """The paper's line as ``reference_line`` reads a line (``paper_line``): unit
    masses and stiffnesses, one exponent, no gap, force, damping or wall."""

    alpha: float
    velocity: np.ndarray
    position: np.ndarray
    left = None
    right = None

    @property
    def n(self) -> int:
        return self.velocity.size

    @property
    def mass(self):
        return np.ones(self.n)

    @property
    def stiffness(self):
        return np.ones(self.n - 1)

    @property
    def gap(self):
        return np.zeros(self.n - 1)

    @property
    def force(self):
        return np.zeros(self.n)


def paper_line(n: int, k: int, alpha: float, *, initial=None) -> PaperLine:
    """The paper's line of ``n`` balls touching at rest, the first ``k`` struck at
    velocity 1; or, with ``initial = (x0, v0)`` (each of shape (N,)), its balls
    displaced by x0 and moving at v0 (``k`` is then unused)."""
    if n < 1 or not 1 <= k <= n:
        raise ValueError(f"need n >= 1 and 1 <= k <= n, got n={n}, k={k}")
    if initial is None:
        v = np.zeros(n)
        v[:k] = 1.0
        return PaperLine(float(alpha), v, np.zeros(n))
    x0, v0 = (np.array(a, dtype=float) for a in initial)
    return PaperLine(float(alpha), v0, x0)


def _integrate_to(rhs, t0, y0, t1, rtol, atol):
    """State at t1 from (t0, y0), with a step ending exactly at t1."""
    if t1 <= t0:
        return y0.copy()
    sol = solve_ivp(rhs, (t0, t1), y0, method="DOP853", rtol=rtol, atol=atol,
                    first_step=t1 - t0)
    if sol.status != 0:
        raise RuntimeError(f"reference integration failed at t={t0}: {sol.message}")
    return sol.y[:, -1]


# ======================================================================================
# The general line: masses, stiffnesses, exponents, gaps, positions, forces, walls.
# ======================================================================================
# Contacts are numbered by their *label* j = -1 .. N-1: contact j joins balls j and
# j + 1, where "ball -1" is the left wall and "ball N" the right wall, both fixed at
# x = 0 (the labels chainrun's event log uses). Internally a label j is the slot
# j + 1 of arrays of N + 1 entries; padded positions (0, x_1 .. x_N, 0) make the
# compression of every slot one expression, delta = xp[s] - xp[s+1] - g[s]. Slots of
# absent walls carry no stiffness and are never active.


@dataclass(frozen=True)
class RefLineSolution:
    """Result of one reference run of a general line, in the line's own units.

    Attributes
    ----------
    n : int
    terminal : bool
        Whether the terminal state was reached before ``t_max``.
    end_time : float
        Time of the last event (the terminal time), or ``t_max``.
    final_position, final_velocity : ndarray, shape (N,)
        State at ``end_time``.
    event_time : ndarray, shape (E,)
    event_contact : ndarray of int64, shape (E,)
        The contact's label: j joins balls j and j+1 (0-based); -1 is the left
        wall's contact, N-1 the right wall's.
    event_kind : ndarray of int8, shape (E,)
        ``OPEN`` (-1) or ``CLOSE`` (+1).
    event_compression : ndarray, shape (E,)
        The contact's compression at the event (zero to rounding).
    separation_time, separation_velocity : ndarray, shape (N,)
        Time and velocity at which each ball last lost its last contact (a wall's
        included); NaN if it never did.
    times : ndarray, shape (T,)
    positions, velocities : ndarray, shape (T, N)
        The state at ``times``; past the end of a terminal run, the free flight that
        follows it; past ``t_max`` of a run that was stopped, NaN.
    steps : int
        Accepted integration steps (first pass).
    units : (float, float, float)
        The mass, length and time the run was integrated in.
    """

    n: int
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
    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    steps: int
    units: tuple
    dissipated: float = 0.0


def _damping_slots(line):
    """Per-slot (N + 1) damping and damping exponent of a line's contacts (0: elastic)."""
    n = line.n
    eta = np.zeros(n + 1)
    bet = np.zeros(n + 1)
    eta[1:n] = getattr(line, "damping", None) if getattr(line, "damping", None) is not None \
        else 0.0
    bet[1:n] = getattr(line, "damping_exponent", None) \
        if getattr(line, "damping_exponent", None) is not None else 0.0
    for s, wall in ((0, line.left), (n, line.right)):
        if wall is not None:
            eta[s] = getattr(wall, "damping", 0.0)
            bet[s] = getattr(wall, "damping_exponent", 0.0)
    return eta, bet


def _slots(line):
    """Per-slot (N + 1) stiffness, exponent, gap and presence of a line's contacts."""
    n = line.n
    kap = np.zeros(n + 1)
    alp = np.ones(n + 1)
    gap = np.zeros(n + 1)
    present = np.zeros(n + 1, dtype=bool)
    kap[1:n] = line.stiffness
    alp[1:n] = line.alpha
    gap[1:n] = line.gap
    present[1:n] = True
    for s, wall in ((0, line.left), (n, line.right)):
        if wall is not None:
            kap[s], alp[s], gap[s], present[s] = wall.stiffness, wall.alpha, wall.gap, True
    return kap, alp, gap, present


def _pad(a):
    """Rows of zeros (the walls) around ``a`` along its first axis."""
    z = np.zeros((1,) + a.shape[1:])
    return np.concatenate((z, a, z))


def reference_units(line) -> tuple[float, float, float]:
    """The (mass, length, time) in which a run of ``line`` is of order 1.

    Mass M: the median mass. Stiffness K and exponent a: those of the contact of
    median stiffness (walls included). Speed V: the largest initial speed; for a line
    at rest, the speed a typical load F (the largest external force, or the force of
    the largest initial compression) gives over its static compression L = (F/K)^(1/a),
    V = sqrt(L F / M). Then the time T = (M V^(1-a) / K)^(1/(a+1)) balances M x'' with
    K x^a, and the length is V T.
    """
    kap, alp, gap, present = _slots(line)
    mass = float(np.median(line.mass))
    speed = float(np.max(np.abs(line.velocity)))
    if not present.any():
        return mass, speed if speed > 0 else 1.0, 1.0
    ks, als = kap[present], alp[present]
    i = int(np.argsort(ks, kind="stable")[ks.size // 2])
    k0, a0 = float(ks[i]), float(als[i])
    if speed == 0.0:
        load = float(np.max(np.abs(line.force)))
        c0 = (_pad(np.asarray(line.position, float))[:-1]
              - _pad(np.asarray(line.position, float))[1:] - gap)[present]
        overlap = float(np.max(c0, initial=0.0))
        if overlap > 0.0:
            load = max(load, k0 * overlap ** a0)
        if load == 0.0:
            return mass, 1.0, 1.0
        length = (load / k0) ** (1.0 / a0)
        speed = np.sqrt(length * load / mass)
    time = (mass * speed ** (1.0 - a0) / k0) ** (1.0 / (a0 + 1.0))
    return mass, speed * time, time


def _closing_time(d0: float, r: float, b: float, floor: float) -> float:
    """Earliest t >= 0 at which d0 + r t + b t^2 / 2 crosses 0 upwards faster than ``floor``.

    The roots of the quadratic come from the cancellation-free pair q / A and C / q,
    q = -(B + sign(B) sqrt(B^2 - 4 A C)) / 2: the textbook formula loses all digits of
    the small root when b t is small against r.
    """
    if d0 >= 0.0 and (r > floor or (r >= -floor and b > 0.0)):
        return 0.0                      # touching (to rounding) and being pressed
    if b == 0.0:
        return -d0 / r if r > floor else np.inf
    a, c = 0.5 * b, d0
    disc = r * r - 4.0 * a * c
    if disc < 0.0:
        return np.inf
    q = -0.5 * (r + np.copysign(np.sqrt(disc), r))
    roots = [q / a] + ([c / q] if q != 0.0 else [])
    best = np.inf
    for t in roots:
        if t >= 0.0 and r + b * t > floor:
            best = min(best, t)
    return best


def line_energy(line, x, v) -> float:
    """Kinetic plus contact energy minus the external forces' potential, at (x, v).

    Conserved by the dynamics: its change is minus the work of the forces not counted,
    none here, so ``line_energy`` is the same at any two instants of a run.
    """
    kap, alp, gap, present = _slots(line)
    x = np.asarray(x, float)
    v = np.asarray(v, float)
    xp = _pad(x)
    d = np.clip(xp[:-1] - xp[1:] - gap, 0.0, None)
    pot = np.sum(np.where(present, kap * d ** (alp + 1.0) / (alp + 1.0), 0.0))
    return float(0.5 * np.sum(line.mass * v * v) + pot - np.sum(line.force * x))


def reference_line(line, *, t_max: float | None = None, times=(), rtol: float = REF_RTOL,
                   atol: float = REF_ATOL, max_events: int = 100_000,
                   units=None) -> RefLineSolution:
    """Run a general ``Line`` to its terminal state, or to ``t_max``.

    Parameters
    ----------
    line : chainrun.solver.model.Line
        The line, in any consistent units (read only: its arrays and walls).
    t_max : float, optional
        Stop time. Required for a line without a terminal state (external forces, or
        two walls); for the others, the run gives up (``terminal=False``) past it.
    times : array_like, shape (T,)
        Non-decreasing, non-negative snapshot times.
    rtol, atol : float
        Tolerances of the DOP853 steps, in the units of the run (``units``).
    max_events : int
        Safety limit on the number of contact events.
    units : (mass, length, time), optional
        The units to integrate in; by default ``reference_units(line)``, in which the
        speeds, compressions and durations are of order 1 (``FLOOR`` and ``atol``
        are absolute there).

    Returns
    -------
    RefLineSolution
    """
    n = line.n
    has_terminal = not np.any(line.force != 0.0) and not (line.left and line.right)
    if t_max is None:
        if not has_terminal:
            raise ValueError("a line with external forces or two walls needs t_max")
        t_max_u = np.inf
    else:
        t_max_u = float(t_max)
    M, L, T = reference_units(line) if units is None else tuple(map(float, units))
    V, F = L / T, M * L / (T * T)

    kap_si, alp, gap_si, present = _slots(line)
    kap = kap_si * L ** alp / F
    gap = gap_si / L
    m = line.mass / M
    acc_free = (line.force / F) / m                     # accelerations in free flight
    accp = _pad(acc_free)
    b_free = accp[:-1] - accp[1:]                       # compressions' second derivative
    t_max = t_max_u / T
    times = np.asarray(times, dtype=float).reshape(-1)
    if np.any(times < 0) or np.any(np.diff(times) < 0):
        raise ValueError("times must be non-negative and non-decreasing")
    ts_u = times / T
    snap_x = np.full((times.size, n), np.nan)
    snap_v = np.full((times.size, n), np.nan)
    isnap = 0
    slots = np.flatnonzero(present)

    def comp(xx):
        xp = _pad(xx)
        return xp[:-1] - xp[1:] - (gap if xx.ndim == 1 else gap[:, None])

    def rate(vv):
        vp = _pad(vv)
        return vp[:-1] - vp[1:]

    # Damping (eta, beta per slot), in the run's units: eta delta^beta delta' is a force.
    eta_si, bet = _damping_slots(line)
    eta = eta_si * L ** bet * V / F
    damped = present & (eta > 0.0)
    # The dissipated energy is integrated as an extra component of the state only when
    # something is damped: an elastic line takes exactly the steps it always took.
    extra = 1 if damped.any() else 0

    def law(d, r):
        # the force of an engaged contact: the law's smooth continuation (no clipping;
        # the contact is released where it reaches 0), sign(d)|d|^alpha for d < 0.
        # d, r: shape (N + 1,) or (N + 1, S)
        k, a, e, b = (p if d.ndim == 1 else p[:, None] for p in (kap, alp, eta, bet))
        ad = np.abs(d)
        elastic = np.where(a == 1.0, d, np.sign(d) * ad ** a)
        return k * elastic + e * np.where(b == 0.0, 1.0, ad ** b) * r

    def law_rate(d, r, acc):
        # d/dt of ``law`` where d > 0 (``acc``: the compressions' second derivative)
        ad = np.maximum(np.abs(d), 1e-300)
        de = np.where(alp == 1.0, r, alp * ad ** (alp - 1.0) * r)
        db = np.where(bet == 0.0, 0.0, bet * ad ** (bet - 1.0) * r * r)
        return kap * de + eta * (db + np.where(bet == 0.0, 1.0, ad ** bet) * acc)

    def make_rhs(act, loose):
        mask = act.astype(float)
        lmask = loose.astype(float)

        def rhs(t, y):
            d, r = comp(y[:n]), rate(y[n:2 * n])
            f = law(d, r) * mask
            a = (f[:-1] - f[1:]) / m + acc_free
            # dissipated power: (F - kappa delta_+^alpha) delta' summed over contacts;
            # an engaged one: eta delta^beta delta'^2; a loose one (released with
            # delta > 0, no force): -kappa delta^alpha delta' (its stored energy is lost)
            power = np.sum(mask * eta * np.where(bet == 0.0, 1.0, np.abs(d) ** bet) * r * r
                           - lmask * kap * np.abs(d) ** alp * r)
            return np.concatenate((y[n:2 * n], a, [power][:extra]))

        return rhs

    def accel(rhs, y):
        """The compressions' second derivative at y."""
        return rate(rhs(0.0, y)[n:2 * n])

    t = 0.0
    x = np.asarray(line.position, float) / L
    v = np.asarray(line.velocity, float) / V
    lost = 0.0                                           # dissipated energy
    d0, r0 = comp(x), rate(v)
    # Compressed, or touching (to rounding) and not parting: active from t = 0; a
    # damped compressed contact whose law gives no force is loose. Touching without
    # moving (|r0| <= FLOOR), a contact is parting when the forces pull its balls apart
    # (its compression's second derivative, with the compressed contacts' forces and
    # the external ones, is negative): it carries no force then, and is not active.
    pressed = present & (d0 > 0)
    pulled = rate(make_rhs(pressed, np.zeros_like(pressed))(0.0, np.r_[x, v, [0.0][:extra]])
                  [n:2 * n]) < 0.0
    touching = (d0 >= -1e-13) & ((r0 > FLOOR) | ((r0 >= -FLOOR) & ~pulled))
    active = present & ((d0 > 0) | touching)
    loose = damped & active & (d0 > 0) & (law(d0, r0) <= 0.0)
    active &= ~loose
    events: list[tuple[float, int, int, float]] = []
    sep_t = np.full(n, np.nan)
    sep_v = np.full(n, np.nan)
    steps = 0

    def switch(s: int, kind: int, tj: float, xx: np.ndarray, vv: np.ndarray) -> None:
        events.append((tj, s - 1, kind, comp(xx)[s]))
        active[s] = kind == CLOSE
        # a damped contact released while still compressed stays loose until it closes
        # again (its law turns positive) or parts (delta crosses 0)
        loose[s] = kind == OPEN and damped[s] and comp(xx)[s] > 0.0
        if kind == OPEN:
            # slot s joins balls s - 1 and s; ball b's contacts are slots b and b + 1
            for b in (s - 1, s):
                if 0 <= b < n and not (active[b] or active[b + 1]):
                    sep_t[b] = tj
                    sep_v[b] = vv[b]

    def restart_consistency(tj: float, xx: np.ndarray, vv: np.ndarray) -> None:
        c, r = comp(xx), rate(vv)
        for s in slots:
            if loose[s] and c[s] <= 0:
                loose[s] = False                          # parted: no event
            if active[s] and c[s] <= 0 and r[s] < -FLOOR:
                switch(s, OPEN, tj, xx, vv)
            elif not active[s] and not loose[s] and c[s] >= 0 and r[s] > FLOOR:
                switch(s, CLOSE, tj, xx, vv)

    def idle(xx, vv) -> bool:
        # Every active contact (if any) touches without load, without moving and
        # without being pressed (balls moving as one body, or a line at rest ahead of
        # a flying striker): its force stays zero, and the free flight may take over.
        # A loose contact (compressed, no force) is integrated until it parts.
        c, r = comp(xx)[active], rate(vv)[active]
        return bool(np.all(c <= 0) and np.all(np.abs(r) <= FLOOR)
                    and np.all(b_free[active] == 0.0) and not loose.any())

    def fly(xx, vv, dt):
        return xx + vv * dt + 0.5 * acc_free * dt * dt, vv + acc_free * dt

    def snap_free(t_to: float) -> None:
        nonlocal isnap
        while isnap < ts_u.size and ts_u[isnap] <= t_to:
            snap_x[isnap], snap_v[isnap] = fly(x, v, ts_u[isnap] - t)
            isnap += 1

    # What each contact watches, by its state: (level, sign after the crossing, kind).
    # "c" is the compression, "g" the law of a damped contact; kind is the event
    # recorded (OPEN, CLOSE) or 0 for a loose contact parting (no event).
    def watches(s):
        if active[s]:
            return [("g" if damped[s] else "c", -1.0, OPEN)]
        if loose[s]:
            return [("g", 1.0, CLOSE), ("c", -1.0, 0)]
        return [("c", 1.0, CLOSE)]

    def levels(y):
        d, r = comp(y[:n]), rate(y[n:2 * n])
        return {"c": d, "g": law(d, r)}

    terminal = False
    while len(events) < max_events:
        if idle(x, v):
            # Free flight, parabolic under the forces: next collision in closed form.
            c, r = comp(x), rate(v)
            best, sbest = np.inf, -1
            for s in slots[~active[slots]]:
                tc = _closing_time(c[s], r[s], b_free[s], FLOOR)
                if tc < best:
                    best, sbest = tc, s
            if sbest < 0 and has_terminal:
                terminal = True
                break
            if t + best > t_max:
                snap_free(t_max)
                x, v = fly(x, v, t_max - t)
                t = t_max
                break
            snap_free(t + best)
            x, v = fly(x, v, best)
            t = t + best
            switch(sbest, CLOSE, t, x, v)
            restart_consistency(t, x, v)
            continue

        # One smooth segment with a fixed state of every contact.
        rhs = make_rhs(active, loose)
        y = np.concatenate((x, v, [lost][:extra]))
        solver = DOP853(rhs, t, y, t_max, rtol=rtol, atol=atol)
        watch = [(s, lv, want, kind) for s in slots for lv, want, kind in watches(s)]
        start = levels(y)
        last_sign = [np.sign(start[lv][s]) for s, lv, _, _ in watch]
        found = None
        while solver.status == "running":
            t_old, y_old = solver.t, solver.y.copy()
            msg = solver.step()
            if solver.status == "failed":
                raise RuntimeError(f"reference integration failed at t={t_old}: {msg}")
            steps += 1
            dense = solver.dense_output()
            tsamp = np.linspace(t_old, solver.t, SAMPLES + 1)[1:]
            ys = dense(tsamp)
            ys[:, -1] = solver.y
            lvs = levels(ys)                              # each shape (N + 1, SAMPLES)
            candidates = []
            for w, (s, lv, want, kind) in enumerate(watch):
                s_prev = last_sign[w]
                t_prev = t_old
                for i in range(SAMPLES):
                    sg = np.sign(lvs[lv][s, i])
                    if sg == want and s_prev != want:
                        tr = brentq(lambda tt: levels(dense(tt))[lv][s], t_prev, tsamp[i],
                                    xtol=1e-16, rtol=1e-15)
                        yr = dense(tr)
                        if lv == "c":
                            speed = rate(yr[n:2 * n])[s]
                        else:
                            speed = law_rate(comp(yr[:n]), rate(yr[n:2 * n]),
                                             accel(rhs, yr))[s]
                        if want * speed > FLOOR:
                            candidates.append((tr, w))
                            break
                    if sg != 0:
                        s_prev = sg
                    t_prev = tsamp[i]
                last_sign[w] = s_prev
            t_stop = min(candidates)[0] if candidates else solver.t
            while isnap < ts_u.size and ts_u[isnap] <= t_stop:
                ysn = _integrate_to(rhs, t_old, y_old, ts_u[isnap], rtol, atol)
                snap_x[isnap], snap_v[isnap] = ysn[:n], ysn[n:2 * n]
                isnap += 1
            if candidates:
                tr, w = min(candidates)
                found = (tr, w, t_old, y_old)
                break

        if found is None:
            t = solver.t
            x, v = solver.y[:n].copy(), solver.y[n:2 * n].copy()
            lost = float(solver.y[-1]) if extra else 0.0
            break                                         # reached t_max

        tr, w, t_old, y_old = found
        s, lv, want, kind = watch[w]
        # Newton on the integrated flow: no step crosses the non-smooth point.
        yr = _integrate_to(rhs, t_old, y_old, tr, rtol, atol)
        for _ in range(8):
            d, r = comp(yr[:n]), rate(yr[n:2 * n])
            if lv == "c":
                dt = -d[s] / r[s]
            else:
                dt = -law(d, r)[s] / law_rate(d, r, accel(rhs, yr))[s]
            if abs(dt) <= 4e-16 * max(1.0, tr):
                break
            tr = tr + dt
            yr = _integrate_to(rhs, t_old, y_old, tr, rtol, atol)
        t = tr
        x, v = yr[:n].copy(), yr[n:2 * n].copy()
        lost = float(yr[-1]) if extra else 0.0
        if kind == 0:
            loose[s] = False                              # a loose contact parted
        else:
            switch(s, kind, t, x, v)
        restart_consistency(t, x, v)

    if terminal:
        snap_free(np.inf)      # free flight at constant velocity from the terminal state
    return RefLineSolution(
        n=n, terminal=terminal, end_time=t * T,
        final_position=x * L, final_velocity=v * V,
        event_time=np.array([e[0] for e in events], dtype=float) * T,
        event_contact=np.array([e[1] for e in events], dtype=np.int64),
        event_kind=np.array([e[2] for e in events], dtype=np.int8),
        event_compression=np.array([e[3] for e in events], dtype=float) * L,
        separation_time=sep_t * T, separation_velocity=sep_v * V,
        times=times, positions=snap_x * L, velocities=snap_v * V, steps=steps,
        units=(M, L, T), dissipated=lost * F * L,
    )


# --------------------------------------------------------------------------------------
# Random short lines: the families the tests draw from, and the accuracy measurement.

#: The families of ``random_line``.
FAMILIES = ("masses", "stiffnesses", "mixed_alpha", "gaps", "heavy_striker",
            "light_striker", "head_on", "right_wall", "left_wall", "two_walls",
            "gravity", "positions")


def random_line(family: str, seed: int):
    """A random short line (N = 2..6, quantities of order 1) of one family, and the
    ``t_max`` it needs (None for a line with a terminal state).

    masses: masses up to a ratio 10; stiffnesses: stiffnesses over a factor 10 and
    masses; mixed_alpha: exponents from {1, 1.5, 2} per contact, masses and
    stiffnesses; gaps: gaps (0.05..0.5) and overlaps (0.01..0.1) among touching
    contacts; heavy_striker / light_striker: a striker 10 times heavier / lighter;
    head_on: the end balls moving inward; right_wall / left_wall: a wall of its own
    stiffness, exponent and gap at one end, the line moving towards it; two_walls: a
    line between walls (t_max); gravity: every ball pulled (force = m g) onto a wall,
    with random velocities (t_max); positions: random initial displacements (some
    contacts compressed, some open) and velocities.
    """
    if family not in FAMILIES:
        raise ValueError(f"unknown family {family!r}")
    from chainrun.solver.model import Line, Wall

    rng = np.random.default_rng([FAMILIES.index(family), seed])
    n = int(rng.integers(2, 7))
    nc = n - 1

    def masses():
        return 10.0 ** rng.uniform(-0.5, 0.5, n)

    def stiff(size):
        return 10.0 ** rng.uniform(-0.5, 0.5, size)

    def alphas(size):
        return rng.choice([1.0, 1.5, 2.0], size)

    def wall():
        return Wall(float(stiff(1)[0]), float(rng.choice([1.0, 1.5, 2.0])),
                    float(rng.uniform(0.0, 0.3)))

    k = int(rng.integers(1, n))      # strikers: 1..N-1
    kw = dict(k=k)
    t_max = None
    if family == "masses":
        line = Line.make(n, mass=masses(), alpha=float(rng.choice([1.0, 1.5, 2.5])), **kw)
    elif family == "stiffnesses":
        line = Line.make(n, mass=masses(), stiffness=stiff(nc),
                         alpha=float(rng.choice([1.0, 1.5])), **kw)
    elif family == "mixed_alpha":
        line = Line.make(n, mass=masses(), stiffness=stiff(nc), alpha=alphas(nc), **kw)
    elif family == "gaps":
        g = rng.choice([0.0, 1.0, -1.0], nc) * rng.uniform(0.05, 0.5, nc)
        g = np.where(g < 0, g / 5.0, g)
        line = Line.make(n, mass=masses(), stiffness=stiff(nc), alpha=alphas(nc),
                         gap=g, **kw)
    elif family in ("heavy_striker", "light_striker"):
        m = np.ones(n)
        m[0] = 10.0 if family == "heavy_striker" else 0.1
        line = Line.make(n, mass=m, alpha=float(rng.choice([1.0, 1.5])), k=1)
    elif family == "head_on":
        v = np.zeros(n)
        v[0], v[-1] = 1.0, -float(rng.uniform(0.3, 1.5))
        line = Line.make(n, mass=masses(), stiffness=stiff(nc), alpha=alphas(nc),
                         velocity=v)
    elif family == "right_wall":
        line = Line.make(n, mass=masses(), stiffness=stiff(nc), alpha=alphas(nc),
                         velocity=rng.uniform(0.0, 1.0, n), right=wall())
    elif family == "left_wall":
        line = Line.make(n, mass=masses(), stiffness=stiff(nc), alpha=alphas(nc),
                         velocity=-rng.uniform(0.0, 1.0, n), left=wall())
    elif family == "two_walls":
        g = rng.uniform(0.0, 0.3, nc)
        line = Line.make(n, mass=masses(), stiffness=stiff(nc), alpha=alphas(nc), gap=g,
                         velocity=rng.uniform(-1.0, 1.0, n), left=wall(), right=wall())
        t_max = 6.0
    elif family == "gravity":
        m = masses()
        g = rng.uniform(0.0, 0.3, nc)
        line = Line.make(n, mass=m, stiffness=stiff(nc), alpha=alphas(nc), gap=g,
                         velocity=rng.uniform(-0.5, 0.5, n), force=0.5 * m,
                         right=wall())
        t_max = 5.0
    else:  # positions
        x = np.cumsum(rng.uniform(-0.12, 0.12, n))[::-1]   # delta_j = x_j - x_{j+1}
        line = Line.make(n, mass=masses(), stiffness=stiff(nc), alpha=alphas(nc),
                         position=x - x.mean(), velocity=rng.uniform(-0.5, 1.0, n))
    return line, t_max


def _measure(seeds: int = 10) -> None:
    """Print the reference's accuracy on ``random_line`` (``python tests/reference.py``)."""
    import time

    worst = {}
    t0 = time.perf_counter()
    runs = 0
    for family in FAMILIES:
        for seed in range(seeds):
            line, t_max = random_line(family, seed)
            base = reference_line(line, t_max=t_max)
            fine = reference_line(line, t_max=t_max, rtol=2.3e-14)
            coarse = reference_line(line, t_max=t_max, rtol=1e-12)
            runs += 1
            e0 = line_energy(line, line.position, line.velocity)
            scale = 0.5 * float(np.sum(line.mass * line.velocity ** 2)) or 1.0
            e1 = line_energy(line, base.final_position, base.final_velocity)
            row = {
                "v fine": np.max(np.abs(base.final_velocity - fine.final_velocity)),
                "v 1e-12": np.max(np.abs(base.final_velocity - coarse.final_velocity)),
                "x fine": np.max(np.abs(base.final_position - fine.final_position)),
                "energy": abs(e1 - e0) / max(scale, abs(e0)),
            }
            row["events"] = len(base.event_time)
            if len(base.event_time) == len(fine.event_time):
                dt = np.abs(base.event_time - fine.event_time)
                row["t fine"] = np.max(dt, initial=0.0)
                row["t/(1+t)"] = np.max(dt / (1.0 + fine.event_time), initial=0.0)
            else:
                row["t fine"] = row["t/(1+t)"] = np.inf
            if line.left is None and line.right is None:
                p0 = np.sum(line.mass * line.velocity) + np.sum(line.force) * base.end_time
                row["momentum"] = abs(np.sum(line.mass * base.final_velocity) - p0)
            for key, val in row.items():
                if val >= worst.get(key, (-1.0,))[0]:
                    worst[key] = (float(val), family, seed)
    print(f"{runs} random lines ({seeds} per family), {time.perf_counter() - t0:.1f} s")
    for key, (val, family, seed) in worst.items():
        print(f"  max {key:8s} {val:.3g}   ({family}, seed {seed})")

    # Closed forms: two balls of any masses, a ball on a wall (closed_forms.py).
    from chainrun.solver.model import Line, Wall
    from closed_forms import contact_duration, two_ball_velocities

    ev = et = 0.0
    for alpha in (1.0, 1.25, 1.5, 2.0, 2.5, 3.0):
        for m1, m2 in ((3.0, 1.0), (1.0, 3.0), (1.0, 10.0), (10.0, 1.0), (0.2, 0.2)):
            u, k = 0.7, 2.3
            r = reference_line(Line.make(2, mass=[m1, m2], stiffness=k, alpha=alpha,
                                         speed=u))
            ev = max(ev, np.max(np.abs(r.final_velocity
                                       - two_ball_velocities(m1, m2, u))) / u)
            tc = contact_duration(m1 * m2 / (m1 + m2), k, alpha, u)
            et = max(et, abs(r.event_time[0] - tc) / tc)
        for sign, side in ((1.0, "right"), (-1.0, "left")):
            r = reference_line(Line.make(1, mass=1.7, velocity=[0.9 * sign],
                                         **{side: Wall(0.6, alpha, 0.25)}))
            ev = max(ev, abs(r.final_velocity[0] + 0.9 * sign) / 0.9)
            tc = contact_duration(1.7, 0.6, alpha, 0.9)
            et = max(et, abs(r.event_time[1] - r.event_time[0] - tc) / tc)
    print(f"closed forms (two balls, ball on a wall): velocity {ev:.2e}, "
          f"contact duration {et:.2e} (relative)")


if __name__ == "__main__":
    import sys

    _measure(int(sys.argv[1]) if len(sys.argv) > 1 else 10)
