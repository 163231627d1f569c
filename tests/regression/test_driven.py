"""Driven lines (moving walls, forces prescribed in time) against closed forms and an
independent scipy integration, and their energy balance with the drives' work.

References here are computed in the tests: the linear driven oscillator's response,
the normal modes of a linear line (numpy), the linear theory of a chain driven above
its cut-off, and a scipy DOP853 integration with events of the whole line, written
below from the equations of motion alone.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from chainrun.solver import Drive, Line, Wall, simulate
from chainrun.solver.physics import line_kinetic_energy, line_potential_energy


def balance(line: Line, sol) -> float:
    """max over the snapshots of |kinetic + contact + dissipated - drive work - initial|,
    relative to the largest of the kinetic energy and the drives' work."""
    t = sol.times
    energy = (line_kinetic_energy(sol.velocities, line.mass)
              + line_potential_energy(sol.positions, line, t) + sol.dissipated)
    scale = max(float(np.max(np.abs(sol.drive_work))),
                float(np.max(line_kinetic_energy(sol.velocities, line.mass))))
    return float(np.max(np.abs(energy - energy[0] - sol.drive_work))) / scale


# --- the linear driven oscillator ------------------------------------------------------


@pytest.mark.parametrize("frequency", [0.05, 0.3, 1.1])
def test_a_ball_between_a_driven_linear_wall_and_a_fixed_one(frequency):
    # m x'' = k1 (w - x + d1) - k2 (x + d2), both contacts pressed at rest (k1 d1 = k2
    # d2), so they never open: x'' + W^2 x = (k1/m) A sin(w t), W^2 = (k1 + k2)/m, from
    # rest: x = B (sin(w t) - (w/W) sin(W t)), B = k1 A / (m (W^2 - w^2))
    m, k1, k2, a, d = 1.7, 2.0, 0.5, 1e-3, 0.05
    line = Line.make(1, mass=m, k=0, stiffness=[], alpha=[], gap=[],
                     left=Wall(k1, 1.0, -d, motion=Drive.sine(a, frequency)),
                     right=Wall(k2, 1.0, -k1 * d / k2))
    t = np.linspace(0.0, 60.0, 121)
    sol = simulate(line, t, t_end=60.0)
    w, big = 2 * math.pi * frequency, math.sqrt((k1 + k2) / m)
    b = k1 * a / (m * (big**2 - w**2))
    x = b * (np.sin(w * t) - w / big * np.sin(big * t))
    v = b * w * (np.cos(w * t) - np.cos(big * t))
    assert sol.outcome.ok and sol.event_time.size == 0
    np.testing.assert_allclose(sol.positions[:, 0], x, rtol=0, atol=1e-9 * np.abs(x).max())
    np.testing.assert_allclose(sol.velocities[:, 0], v, rtol=0, atol=1e-9 * np.abs(v).max())
    assert balance(line, sol) < 1e-10


def test_a_ball_held_by_precompression_against_a_driven_wall_with_a_ramp():
    # the ball pressed against the left wall by a constant force F0 (one wall's
    # precompression); the wall w(t) = A r(t/T) sin(w t). Then y = x - x0 obeys
    # y'' + W^2 y = W^2 w(t), W^2 = k/m, whose solution from rest is the convolution
    # y(t) = W int_0^t sin(W (t - s)) w(s) ds (Duhamel), computed here by quadrature
    from scipy.integrate import quad

    m, k, f0, a, f, ramp = 0.8, 3.0, 0.2, 1e-3, 0.25, 6.0
    line = Line.make(1, mass=m, stiffness=[], alpha=[], gap=[], force=[-f0],
                     position=[-f0 / k], velocity=[0.0],
                     left=Wall(k, 1.0, 0.0, motion=Drive.sine(a, f, ramp)))
    t = np.linspace(0.0, 20.0, 41)
    sol = simulate(line, t, t_end=20.0)
    big = math.sqrt(k / m)
    drive = line.left.motion
    y = np.array([big * quad(lambda s: math.sin(big * (tt - s)) * float(drive(s)), 0.0, tt,
                             points=[ramp] if tt > ramp else None, limit=200,
                             epsabs=1e-15, epsrel=1e-13)[0] for tt in t])
    np.testing.assert_allclose(sol.positions[:, 0] + f0 / k, y, rtol=0,
                               atol=1e-9 * np.abs(y).max())
    assert balance(line, sol) < 1e-10


# --- an independent integration of a small driven line ---------------------------------


def scipy_line(line: Line, times, t_end: float, rtol=1e-13, atol=1e-16):
    """Positions and velocities of an elastic ``line`` at ``times`` by scipy's DOP853,
    restarted at every contact's opening and closing (events of solve_ivp) and at the
    drives' breakpoints: between them the active set is fixed and the motion smooth."""
    n, mass = line.n, np.asarray(line.mass, dtype=float)
    left, right = line.left, line.right
    contacts = []  # (ball before, ball after, kappa, alpha, gap); -1 and n are the walls
    if left is not None:
        contacts.append((-1, 0, left.stiffness, left.alpha, left.gap))
    contacts += [(j, j + 1, line.stiffness[j], line.alpha[j], line.gap[j]) for j in range(n - 1)]
    if right is not None:
        contacts.append((n - 1, n, right.stiffness, right.alpha, right.gap))
    motion = {-1: left.motion if left is not None else None,
              n: right.motion if right is not None else None}

    def at(y, t, i, d=0):
        if i in motion:
            return float(motion[i](t, d)) if motion[i] is not None else 0.0
        return y[i + d * n]

    def comp(t, y, c):
        i, j, _, _, g = contacts[c]
        return at(y, t, i) - at(y, t, j) - g

    def rhs(active):
        def f(t, y):
            acc = np.asarray(line.force, dtype=float).copy()
            for b, drive in line.drives:
                acc[b] += float(drive(t))
            for c, (i, j, kappa, alpha, _) in enumerate(contacts):
                if active[c]:
                    d = comp(t, y, c)
                    force = kappa * math.copysign(abs(d) ** alpha, d)
                    if i >= 0:
                        acc[i] -= force
                    if j < n:
                        acc[j] += force
            return np.concatenate([y[n:], acc / mass])
        return f

    y = np.concatenate([line.position, line.velocity]).astype(float)
    active = [comp(0.0, y, c) > 0.0 for c in range(len(contacts))]
    drives = [m for m in motion.values() if m is not None] + [d for _, d in line.drives]
    breaks = sorted({float(b) for d in drives for b in d.breakpoints} | {t_end})
    out, t = {}, 0.0
    while t < t_end:
        stop = min(b for b in breaks if b > t)
        events = []
        for c in range(len(contacts)):
            def event(tt, yy, c=c):
                return comp(tt, yy, c)
            event.terminal, event.direction = True, (-1 if active[c] else 1)
            events.append(event)
        sol = solve_ivp(rhs(active), (t, stop), y, method="DOP853", rtol=rtol, atol=atol,
                        events=events, dense_output=True)
        end = float(sol.t[-1])
        for tt in times:
            if t <= tt <= end:
                out.setdefault(float(tt), sol.sol(tt))
        y = sol.y[:, -1].copy()
        for c in range(len(contacts)):
            if sol.status == 1 and sol.t_events[c].size and sol.t_events[c][0] == end:
                active[c] = not active[c]
        t = end
    table = np.array([out[float(tt)] for tt in times])
    return table[:, :n], table[:, n:]


def test_a_small_driven_hertz_line_against_scipy():
    # three unequal balls, gaps, a Hertz left wall shaken by two sines (one ramped) that
    # it leaves and meets again, a fixed right wall across a gap: contacts open and close
    line = Line.make(3, mass=[1.0, 1.5, 0.8], stiffness=[1.0, 1.3], alpha=1.5,
                     gap=[0.0, 0.002], k=0,
                     left=Wall(2.0, 1.5, 0.0, motion=Drive.of_sines(
                         [dict(amplitude=0.05, frequency=0.15, ramp=3.0),
                          dict(amplitude=0.01, frequency=0.4)])),
                     right=Wall(1.0, 1.5, 0.01))
    t = np.linspace(0.0, 40.0, 81)
    sol = simulate(line, t, t_end=40.0)
    x, v = scipy_line(line, t, 40.0)
    assert sol.event_time.size >= 10  # the balls leave the walls and each other
    np.testing.assert_allclose(sol.positions, x, rtol=0, atol=1e-8 * np.abs(x).max())
    np.testing.assert_allclose(sol.velocities, v, rtol=0, atol=1e-8 * np.abs(v).max())
    assert balance(line, sol) < 1e-10


def test_a_force_in_time_on_a_ball_against_scipy():
    # a ramped force on the middle ball of a free Hertz line with gaps, and a sine on
    # the last: the balls meet and part
    line = Line.make(3, mass=[1.0, 1.5, 0.8], stiffness=1.0, alpha=1.5,
                     gap=[0.001, 0.002], k=0,
                     drives=[(1, Drive.sine(0.02, 0.3, ramp=2.0)),
                             (2, Drive.sine(0.01, 0.05))])
    t = np.linspace(0.0, 30.0, 61)
    sol = simulate(line, t, t_end=30.0)
    x, v = scipy_line(line, t, 30.0)
    assert sol.event_time.size >= 2
    np.testing.assert_allclose(sol.positions, x, rtol=0, atol=1e-8 * np.abs(x).max())
    np.testing.assert_allclose(sol.velocities, v, rtol=0, atol=1e-8 * np.abs(v).max())
    assert balance(line, sol) < 1e-10
    # the momentum check counts the drives' impulse, int d(t) dt
    assert sol.diagnostics.momentum_error < 1e-12


# --- the energy balance with the drives' work ----------------------------------------------


@pytest.mark.parametrize("case", ["damped wall and contacts", "damped, driven ball",
                                  "dashpot, both walls moving"])
def test_energy_balance_with_the_drives_work_on_damped_lines(case):
    if case == "damped wall and contacts":
        line = Line.make(4, mass=[1.0, 0.7, 1.2, 0.9], stiffness=1.0, alpha=1.5, gap=-1e-3,
                         k=0, damping=0.3, damping_exponent=0.5,
                         left=Wall(1.5, 1.5, -1e-3, damping=0.2, damping_exponent=0.5,
                                   motion=Drive.sine(0.01, 0.2, ramp=3.0)),
                         right=Wall(1.0, 1.5, -1e-3))
    elif case == "damped, driven ball":
        line = Line.make(3, mass=1.0, stiffness=1.0, alpha=1.5, gap=[0.0, 0.001], k=0,
                         damping=0.2, damping_exponent=0.25, right=Wall(1.0, 1.5),
                         drives=[(0, Drive.sine(0.05, 0.1, ramp=4.0))])
    else:
        line = Line.make(3, mass=1.0, stiffness=1.0, alpha=1.0, gap=-0.01, k=0,
                         damping=0.1, left=Wall(1.0, 1.0, -0.01, damping=0.1,
                                                motion=Drive.sine(0.005, 0.12)),
                         right=Wall(1.0, 1.0, -0.01, motion=Drive.sine(0.003, 0.31, 1.0)))
    t = np.linspace(0.0, 40.0, 161)
    sol = simulate(line, t, t_end=40.0)
    assert sol.outcome.ok and sol.dissipated[-1] > 0.0 and np.any(sol.drive_work)
    assert balance(line, sol) < 1e-10
    assert sol.diagnostics.energy_error < 1e-10


# --- a drive from samples --------------------------------------------------------------


def test_a_spline_through_samples_of_a_sine_drives_as_the_sine():
    from scipy.interpolate import CubicSpline

    a, f, last = 0.005, 0.2, 20.0
    samples = np.linspace(0.0, last, 401)
    spline = Drive.from_samples(samples, a * np.sin(2 * np.pi * f * samples))

    def line(motion):
        return Line.make(2, mass=1.0, stiffness=1.0, alpha=1.5, gap=0.0, k=0,
                         left=Wall(1.0, 1.5, -0.02, motion=motion), right=Wall(1.0, 1.5, -0.02))

    fine = np.linspace(0.0, last, 20001)
    # the spline's own accuracy, measured with scipy's spline through the same samples
    gap = float(np.max(np.abs(CubicSpline(samples, a * np.sin(2 * np.pi * f * samples))(fine)
                              - a * np.sin(2 * np.pi * f * fine))))
    assert 0.0 < gap < 1e-9
    np.testing.assert_allclose(spline(fine), CubicSpline(
        samples, a * np.sin(2 * np.pi * f * samples))(fine), rtol=0, atol=1e-16)
    t = np.linspace(0.0, last, 81)
    by_file = simulate(line(spline), t, t_end=last)
    by_sine = simulate(line(Drive.sine(a, f)), t, t_end=last)
    # a wall off by at most `gap` moves the balls by about as much (off resonance)
    np.testing.assert_allclose(by_file.positions, by_sine.positions, rtol=0, atol=100 * gap)
    assert balance(line(spline), by_file) < 1e-10


def test_a_breakpoint_ends_a_step():
    # samples of a ramp t^3 whose last slope is not 0: the wall stops dead at the last
    # time (held), its velocity jumps there; a step across that would lose its order.
    # The linear oscillator against it, from rest, has a closed form on each side.
    m, k, d, last = 1.0, 1.0, 0.1, 3.0
    samples = np.linspace(0.0, last, 7)
    drive = Drive.from_samples(samples, 1e-3 * samples**3)  # a cubic: the spline is exact
    assert list(drive.breakpoints) == list(samples[1:])
    line = Line.make(1, mass=m, k=0, stiffness=[], alpha=[], gap=[],
                     left=Wall(k, 1.0, -d, motion=drive), right=Wall(k, 1.0, -d))
    t = np.linspace(0.0, 8.0, 33)
    sol = simulate(line, t, t_end=8.0)
    # x'' + 2 x = w(t) (k = m = 1): with w = c t^3, a particular solution is
    # c (t^3 / 2 - 3 t / 2); then, with w = c T^3 held, x = c T^3 / 2 + free oscillation
    c, big = 1e-3, math.sqrt(2.0)

    def before(tt):
        x = c * (tt**3 / 2 - 1.5 * tt) + 1.5 * c / big * np.sin(big * tt)
        v = c * (1.5 * tt**2 - 1.5) + 1.5 * c * np.cos(big * tt)
        return x, v

    x_t, v_t = before(last)
    held = c * last**3 / 2
    x_after = held + (x_t - held) * np.cos(big * (t - last)) + v_t / big * np.sin(big * (t - last))
    x = np.where(t <= last, before(t)[0], x_after)
    np.testing.assert_allclose(sol.positions[:, 0], x, rtol=0, atol=1e-10 * np.abs(x).max())
    assert balance(line, sol) < 1e-10


# --- the linear spectrum of a driven line ---------------------------------------------


def _modes(n: int, stiffness: float, mass: float) -> np.ndarray:
    """omega_j = 2 sqrt(K/m) sin(j pi / (2 (N + 1))), j = 1..N: both ends walls."""
    return 2 * math.sqrt(stiffness / mass) * np.sin(np.arange(1, n + 1) * math.pi / (2 * (n + 1)))


def test_a_line_between_walls_driven_at_a_mode_grows_without_bound():
    # N = 5 unit balls and 6 unit springs between two walls, every contact pressed (it
    # never opens), the left wall shaken: at a mode's frequency the response grows
    # linearly (undamped resonance), between two modes it stays bounded. And the
    # whole response is the modal solution of the linear system, computed here
    n, a, d = 5, 1e-5, 0.05
    omega = _modes(n, 1.0, 1.0)
    big = np.diag(np.full(n, 2.0)) - np.diag(np.ones(n - 1), 1) - np.diag(np.ones(n - 1), -1)
    values, vectors = np.linalg.eigh(big)
    np.testing.assert_allclose(np.sqrt(values), omega, rtol=1e-12)
    t = np.linspace(0.0, 400.0, 801)
    amplitude = {}
    for name, w in (("mode 2", omega[1]), ("between 2 and 3", 0.5 * (omega[1] + omega[2]))):
        line = Line.make(n, mass=1.0, stiffness=1.0, alpha=1.0, gap=-d, k=0,
                         left=Wall(1.0, 1.0, -d, motion=Drive.sine(a, w / (2 * math.pi))),
                         right=Wall(1.0, 1.0, -d))
        sol = simulate(line, t, t_end=400.0)
        # x'' + K x = e_1 a sin(w t): mode j gets q_j'' + W_j^2 q_j = phi_j1 a sin(w t)
        x = np.zeros((t.size, n))
        for wj, phi in zip(np.sqrt(values), vectors.T):
            g = phi[0] * a
            if abs(wj - w) < 1e-12:  # at resonance: g/(2w^2) (sin(w t) - w t cos(w t))
                q = g / (2 * w**2) * (np.sin(w * t) - w * t * np.cos(w * t))
            else:
                q = g / (wj**2 - w**2) * (np.sin(w * t) - w / wj * np.sin(wj * t))
            x += np.outer(q, phi)
        np.testing.assert_allclose(sol.positions, x, rtol=0, atol=1e-9 * np.abs(x).max())
        early, late = np.abs(sol.positions[t <= 50.0]).max(), np.abs(sol.positions[t >= 350.0]).max()
        amplitude[name] = late / early
        assert abs(sol.positions).max() < 0.5 * d  # every contact stays pressed
    assert amplitude["mode 2"] > 4.0
    assert amplitude["between 2 and 3"] < 2.0


def test_a_precompressed_chain_driven_above_its_cutoff_decays_at_the_linear_rate():
    # a Hertz chain between walls under a load F0, every contact of stiffness
    # K = 3/2 kappa^(2/3) F0^(1/3) at rest; driven by its left wall at w > 2 sqrt(K/m)
    # the displacement falls by e^-mu per ball, cosh(mu/2) = w/w_c; below it, the wave
    # crosses the chain
    from chainrun.solver.model import precompress

    n, f0, a = 14, 1.0, 1e-6
    kk = 1.5 * f0 ** (1.0 / 3.0)  # kappa = 1
    cutoff = 2.0 * math.sqrt(kk)
    period = 2 * math.pi / cutoff
    reach = {}
    for ratio in (1.5, 0.6):
        w = ratio * cutoff
        ramp = 40 * period
        line = precompress(Line.make(n, mass=1.0, stiffness=1.0, alpha=1.5, k=0,
                                     left=Wall(1.0, 1.5, motion=Drive.sine(
                                         a, w / (2 * math.pi), ramp)),
                                     right=Wall(1.0, 1.5)), f0)
        t_end = ramp + 20 * period
        t = np.linspace(ramp, t_end, 801)
        sol = simulate(line, t, t_end=t_end)
        amp = np.abs(sol.positions - line.position).max(axis=0)
        reach[ratio] = amp / a
        if ratio > 1.0:
            mu = 2.0 * math.acosh(ratio)
            rates = np.log(amp[:4] / amp[1:5])
            np.testing.assert_allclose(rates, mu, rtol=0.02)
    # (past a few balls what is left above the cut-off is what the ramp's start put
    # into the pass band: some 1e-6 of the drive, against e^-9mu = 3e-8)
    assert reach[1.5][9] < 1e-4 and reach[0.6][9] > 0.1
