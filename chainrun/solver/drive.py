"""Prescribed functions of time: a driven wall's displacement, a ball's driving force.

A ``Drive`` is a function u(t) for t >= 0, in the line's own units:

* a sum of sines, each ``A sin(2 pi f t)`` times its smooth start ``r(t / T)``:

      u(t) = sum_i A_i r(t / T_i) sin(2 pi f_i t),
      r(s) = 10 s^3 - 15 s^4 + 6 s^5 for 0 <= s < 1, and 1 from s = 1 on

  (no ramp, T = 0: r = 1). Each sine starts at 0 with velocity ``2 pi f A``; with a
  ramp its value, first and second derivatives start at 0, and the ramp reaches 1 at
  T with its first and second derivatives 0 again. The ramp is the quintic
  "smootherstep", the polynomial of least degree that does both: a driven wall's
  position, velocity and acceleration, and so its contact force and that force's
  rate, start from rest and join the steady sine without a jump. Its third derivative
  jumps at T (and at 0), where the drive has a breakpoint.
* samples ``(t_i, u_i)``, ``t_0 = 0`` < t_1 < ..., joined by the cubic spline through
  them with not-a-knot ends (``scipy.interpolate.CubicSpline``'s default: twice
  continuously differentiable, fourth-order accurate), and held at ``u_last`` after
  the last time (a drive that should stop smoothly ends its samples at rest).
  Every sample time is a breakpoint.

Between breakpoints u is analytic: on each piece it is a sum of terms
``p(s) sin(omega s + phi)``, s the time since the piece's start and p a polynomial
of degree <= 5 (``Drive.pieces``), whose Taylor series at any time the kernels compute
exactly (``_drive``); every step of the solver ends at a breakpoint, as it ends at a
contact event, so no step crosses one.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

#: Coefficients of the ramp r(s) = 10 s^3 - 15 s^4 + 6 s^5, by power of s (0..5).
RAMP = (0.0, 0.0, 0.0, 10.0, -15.0, 6.0)
#: Terms of a piece: the polynomial's degree + 1 coefficients, then omega and phi.
POLY = 6
TERM = POLY + 2


@dataclass(frozen=True)
class Sine:
    """One sine ``amplitude * r(t / ramp) * sin(2 pi frequency t)`` (see the module).

    ``frequency`` in cycles per unit of time (Hz in SI), > 0; ``ramp`` >= 0 (0: none).
    """

    amplitude: float
    frequency: float
    ramp: float = 0.0

    def __post_init__(self):
        for name in ("amplitude", "frequency", "ramp"):
            value = getattr(self, name)
            if not math.isfinite(value):
                raise ValueError(f"{name} must be finite, got {value!r}")
        if not self.frequency > 0.0:
            raise ValueError(f"frequency must be > 0, got {self.frequency!r}")
        if self.ramp < 0.0:
            raise ValueError(f"ramp must be >= 0, got {self.ramp!r}")


def _shifted(coefficients, shift: float, scale: float) -> np.ndarray:
    """Coefficients in s of sum_j a_j ((s + shift) / scale)^j: the polynomial of
    ``coefficients`` (by power) moved to start at ``shift`` and stretched by
    ``scale``."""
    a = np.asarray(coefficients, dtype=float)
    out = np.zeros(POLY)
    for j, aj in enumerate(a):
        if aj == 0.0:
            continue
        for i in range(j + 1):
            out[i] += aj * math.comb(j, i) * shift ** (j - i) / scale ** j
    return out


@dataclass(frozen=True, eq=False)
class Drive:
    """A prescribed function of time u(t), t >= 0 (see the module): a sum of ``sines``,
    or the spline through ``times`` (shape (M,), from 0, increasing) and ``values``
    (shape (M,)), held after the last time. Build it with ``Drive.of_sines`` or
    ``Drive.from_samples``."""

    sines: tuple[Sine, ...] = ()
    times: np.ndarray | None = None
    values: np.ndarray | None = None

    def __post_init__(self):
        if (self.times is None) == (not self.sines):
            raise ValueError("a drive is sines or samples, one of the two")
        if self.times is not None:
            t = np.asarray(self.times, dtype=float)
            u = np.asarray(self.values, dtype=float)
            if t.ndim != 1 or u.shape != t.shape or t.size < 2:
                raise ValueError("a drive's samples need at least two times, each with "
                                 "one value")
            if not (np.all(np.isfinite(t)) and np.all(np.isfinite(u))):
                raise ValueError("a drive's samples must be finite")
            if t[0] != 0.0:
                raise ValueError(f"a drive's samples start at t = 0, got {t[0]!r}")
            if np.any(np.diff(t) <= 0.0):
                i = int(np.flatnonzero(np.diff(t) <= 0.0)[0]) + 1
                raise ValueError(f"a drive's times must increase: {t[i]!r} after "
                                 f"{t[i - 1]!r} (row {i})")
            t.setflags(write=False)
            u.setflags(write=False)
            object.__setattr__(self, "times", t)
            object.__setattr__(self, "values", u)

    @classmethod
    def of_sines(cls, sines) -> Drive:
        """A sum of sines: ``Sine`` objects or tables (dicts) of their fields."""
        items = tuple(s if isinstance(s, Sine) else Sine(**s) for s in sines)
        if not items:
            raise ValueError("a sum of sines needs at least one")
        return cls(sines=items)

    @classmethod
    def sine(cls, amplitude: float, frequency: float, ramp: float = 0.0) -> Drive:
        return cls(sines=(Sine(float(amplitude), float(frequency), float(ramp)),))

    @classmethod
    def from_samples(cls, times, values) -> Drive:
        return cls(times=np.array(times, dtype=float), values=np.array(values, dtype=float))

    # ---- its pieces ------------------------------------------------------------------

    def pieces(self, time_scale: float = 1.0, value_scale: float = 1.0):
        """The pieces of u between breakpoints, in units of ``time_scale`` and
        ``value_scale``.

        Returns
        -------
        starts : ndarray, shape (P,)
            Each piece's start (the first is 0); piece i lasts until ``starts[i + 1]``,
            the last forever.
        terms : list of ndarray, each shape (Q_i, TERM)
            Piece i's terms: ``u = sum_q (sum_j c_qj s^j) sin(omega_q s + phi_q)``, s the
            time since the piece's start; each row holds c_q0..c_q5, omega_q, phi_q.
        """
        if time_scale == 1.0 and value_scale == 1.0:
            return self._pieces
        return self._pieces_in(float(time_scale), float(value_scale))

    @functools.cached_property
    def _pieces(self):
        return self._pieces_in(1.0, 1.0)

    def _pieces_in(self, ts: float, us: float):
        if self.times is not None:
            from scipy.interpolate import CubicSpline

            t, u = self.times, self.values
            spline = CubicSpline(t, u)
            terms = []
            for i in range(t.size - 1):
                row = np.zeros(TERM)
                for k in range(4):  # spline.c[3 - k, i]: the coefficient of (t - t_i)^k
                    row[k] = spline.c[3 - k, i] * ts ** k / us
                row[POLY + 1] = 0.5 * math.pi  # (sin(pi/2) = 1 exactly)
                terms.append(row[None, :])
            hold = np.zeros(TERM)
            hold[0] = u[-1] / us
            hold[POLY + 1] = 0.5 * math.pi
            terms.append(hold[None, :])
            return t / ts, terms
        starts = sorted({0.0} | {s.ramp for s in self.sines if s.ramp > 0.0})
        terms = []
        for a in starts:
            rows = []
            for s in self.sines:
                omega = 2.0 * math.pi * s.frequency
                row = np.zeros(TERM)
                if a < s.ramp:  # ramping: a piece inside [0, T)
                    poly = _shifted(RAMP, a, s.ramp)
                    row[:POLY] = s.amplitude * poly * ts ** np.arange(POLY) / us
                else:
                    row[0] = s.amplitude / us
                row[POLY] = omega * ts
                row[POLY + 1] = math.fmod(omega * a, 2.0 * math.pi)
                rows.append(row)
            terms.append(np.array(rows))
        return np.array(starts) / ts, terms

    @property
    def breakpoints(self) -> np.ndarray:
        """The times > 0 where a piece ends and the next starts; shape (B,)."""
        return self.pieces()[0][1:]

    # ---- its values ------------------------------------------------------------------

    def __call__(self, t, derivative: int = 0) -> np.ndarray:
        """u(t) (or its ``derivative``-th derivative, 0..3) at times ``t`` >= 0; any
        shape. Just after a breakpoint, the next piece's."""
        t = np.asarray(t, dtype=float)
        starts, terms = self.pieces()
        piece = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, None)
        out = np.zeros(t.shape)
        for i, rows in enumerate(terms):
            at = piece == i
            if not np.any(at):
                continue
            s = t[at] - starts[i]
            for row in rows:
                out[at] += _term(row, s, derivative)
        return out[()] if out.ndim == 0 else out

    def integral(self, t) -> np.ndarray:
        """int_0^t u(s) ds (a driven ball's impulse, for a force), exactly: on each
        piece by parts, int p q = p Q1 - p' Q2 + p'' Q3 - ..., Q_k the k-th
        antiderivative of the sine, sin(omega s + phi - k pi / 2) / omega^k."""
        t = np.asarray(t, dtype=float)
        starts, terms = self.pieces()
        out = np.zeros(t.shape)
        for i, rows in enumerate(terms):
            end = np.minimum(t, starts[i + 1] if i + 1 < len(starts) else np.inf)
            span = np.clip(end - starts[i], 0.0, None)
            for row in rows:
                out += _term_integral(row, span) - _term_integral(row, np.zeros(1))[0]
        return out[()] if out.ndim == 0 else out

    @property
    def speed(self) -> float:
        """A typical |u'|: sum of 2 pi f |A| over the sines, or the largest slope
        between samples."""
        if self.times is not None:
            return float(np.max(np.abs(np.diff(self.values) / np.diff(self.times))))
        return float(sum(2.0 * math.pi * s.frequency * abs(s.amplitude) for s in self.sines))

    @property
    def size(self) -> float:
        """A typical |u|: sum of |A| over the sines, or the largest |u_i|."""
        if self.times is not None:
            return float(np.max(np.abs(self.values)))
        return float(sum(abs(s.amplitude) for s in self.sines))

    def describe(self) -> str:
        """One line for a person."""
        if self.times is not None:
            return (f"spline through {self.times.size} samples to t = "
                    f"{self.times[-1]:.6g}, held after")
        parts = [f"{s.amplitude:.6g} sin(2 pi {s.frequency:.6g} t)"
                 + (f" with a ramp of {s.ramp:.6g}" if s.ramp else "") for s in self.sines]
        return " + ".join(parts)


def _term(row: np.ndarray, s: np.ndarray, derivative: int) -> np.ndarray:
    """The ``derivative``-th derivative of p(s) sin(omega s + phi) (one term's row)."""
    c, omega, phi = row[:POLY], row[POLY], row[POLY + 1]
    total = np.zeros(np.shape(s))
    # Leibniz: (p q)^(n) = sum_i C(n, i) p^(i) q^(n-i), q^(m) = omega^m sin(. + m pi/2)
    for i in range(derivative + 1):
        dp = np.polynomial.polynomial.polyval(s, np.polynomial.polynomial.polyder(c, i)
                                              if i else c)
        m = derivative - i
        dq = omega ** m * np.sin(omega * s + phi + 0.5 * m * math.pi) if m else \
            np.sin(omega * s + phi)
        total = total + math.comb(derivative, i) * dp * dq
    return total


def _term_integral(row: np.ndarray, s: np.ndarray) -> np.ndarray:
    """An antiderivative of p(s) sin(omega s + phi) (one term's row), at s."""
    c, omega, phi = row[:POLY], row[POLY], row[POLY + 1]
    if omega == 0.0:
        return np.polynomial.polynomial.polyval(
            s, np.polynomial.polynomial.polyint(c)) * math.sin(phi)
    total = np.zeros(np.shape(s))
    for k in range(POLY):
        dp = np.polynomial.polynomial.polyval(s, np.polynomial.polynomial.polyder(c, k)
                                              if k else c)
        total = total + (-1) ** k * dp * np.sin(omega * s + phi - 0.5 * (k + 1) * math.pi) \
            / omega ** (k + 1)
    return total
