"""Units of a run's quantities: what each is measured in, and how a person reads it.

This module owns the unit of every quantity chainrun writes (``UNITS``, by the run's
``units``, ``"paper"`` or ``"si"``) and how values are shown: in SI scaled to a readable
prefix (``µs``, ``mm``, ``kN``), in the paper's units as "paper units". The store writes
the unit strings; the plots, movies and summaries take their labels from here.

A prefix is chosen for a whole set of values (an axis, a column) so that the largest
magnitude falls in [1, 1000): ``scale_for("time", "si", [0, 2.2e-4])`` gives
``Scaled(factor=1e6, unit="µs")``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

__all__ = ["PAPER", "SWEPT_QUANTITY", "UNITS", "Scaled", "axis_label", "end_phrase",
           "format_digits", "format_measured", "format_supported", "format_value",
           "format_with_error", "scale_for", "scale_for_column",
           "supported_format"]

#: How the paper's units are named in labels: every coefficient of its equation is 1.
PAPER = "paper units"

#: H5MD ``unit`` of each quantity, by the units of the run. The paper's units are
#: written "1" (docs/schema.md gives their meaning in kg, m and s).
UNITS: dict[str, dict[str, str]] = {
    "si": {"time": "s", "position": "m", "velocity": "m/s", "mass": "kg", "force": "N",
           "energy": "J", "momentum": "kg m/s", "stiffness": "N m-alpha", "alpha": "1",
           "gap": "m", "diameter": "m", "frequency": "Hz", "angular_frequency": "rad/s",
           "linear_stiffness": "N/m"},
    "paper": dict.fromkeys(("time", "position", "velocity", "mass", "force", "energy",
                            "momentum", "stiffness", "alpha", "gap", "diameter",
                            "frequency", "angular_frequency", "linear_stiffness"), "1"),
}

#: The quantity of a swept key's values, by the key's last part (``chain.speed``:
#: a velocity), for their unit: a key not here is a number without one (a seed, K).
SWEPT_QUANTITY = {"speed": "velocity", "precompression": "force", "diameter": "diameter",
                  "gap": "gap", "force": "force", "t_end": "time", "mass": "mass",
                  "restitution_speed": "velocity", "frequency": "frequency",
                  "amplitude": "position", "ramp": "time"}

#: The unit a prefix goes on, for each SI quantity that takes one: a mass in grams, a
#: momentum in newton seconds (kg m/s), a velocity on its metre.
_BASE = {"time": ("", "s"), "position": ("", "m"), "gap": ("", "m"), "diameter": ("", "m"),
         "velocity": ("", "m/s"), "force": ("", "N"), "energy": ("", "J"),
         "momentum": ("", "N s"), "mass": ("", "g"), "frequency": ("", "Hz"),
         "angular_frequency": ("", "rad/s"), "linear_stiffness": ("", "N/m")}
#: a mass is written in grams: 1 kg is 1000 g
_IN_BASE = {"mass": 1e3}
_PREFIXES = ((1e12, "T"), (1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"),
             (1e-6, "µ"), (1e-9, "n"), (1e-12, "p"), (1e-15, "f"))


@dataclass(frozen=True)
class Scaled:
    """Values times ``factor`` are in ``unit`` (``""``: a pure number)."""

    factor: float
    unit: str

    def __call__(self, values):
        """``values`` in ``unit``."""
        return np.asarray(values, dtype=float) * self.factor


def _largest(values) -> float:
    a = np.abs(np.asarray(values, dtype=float))
    a = a[np.isfinite(a)]
    return float(a.max()) if a.size else 0.0


def scale_for(quantity: str, units: str, values=()) -> Scaled:
    """The factor and unit that show ``values`` of ``quantity`` readably.

    In SI the prefix puts the largest magnitude of ``values`` in [1, 1000) (no prefix
    when they are all 0 or none are finite); a quantity without a prefixed unit
    (a stiffness, an exponent) keeps its SI unit. In the paper's units the factor is 1
    and the unit ``PAPER``.
    """
    if units != "si":
        return Scaled(1.0, "" if quantity == "alpha" else PAPER)
    if quantity not in _BASE:
        unit = UNITS["si"].get(quantity, "")
        return Scaled(1.0, "" if unit == "1" else unit)
    to_base = _IN_BASE.get(quantity, 1.0)
    top = _largest(values) * to_base
    size = 1.0
    if top > 0.0:
        for size, _ in _PREFIXES:
            if top >= size * (1.0 - 1e-12):
                break
    prefix = dict(_PREFIXES)[size]
    return Scaled(to_base / size, prefix + _BASE[quantity][1])


def scale_for_column(quantity: str, units: str, values=()) -> Scaled:
    """The factor and unit for a column of ``values`` read one by one: the prefix that
    puts their median magnitude (of those not 0) in [1, 1000), so that values spread
    over a few decades read without leading zeros (0.116, 0.267 and 1.64 mm/s are 116,
    267 and 1644 µm/s); as ``scale_for`` otherwise."""
    a = np.abs(np.asarray(values, dtype=float))
    a = a[np.isfinite(a) & (a > 0.0)]
    return scale_for(quantity, units, [float(np.median(a))] if a.size else [])


def law_unit(quantity: str, exponents, units: str) -> str:
    """The unit of a force law's coefficient in ``units``: kappa of kappa delta^alpha
    (``"stiffness"``, ``exponents`` the alphas) in N m-alpha, eta of eta delta^beta
    d(delta)/dt (``"damping"``, the betas) in N s m-(1+beta); where every contact has
    one exponent, the unit itself (N m-1.5, N s m-1.25). The paper's units: "1"."""
    if units != "si":
        return UNITS["paper"]["stiffness"]
    e = np.asarray(exponents, dtype=np.float64).reshape(-1)
    e = e[np.isfinite(e)]
    one = e.size > 0 and bool(np.all(e == e[0]))
    if quantity == "stiffness":
        return f"N m-{float(e[0]):g}" if one else UNITS["si"]["stiffness"]
    return f"N s m-{1.0 + float(e[0]):g}" if one else "N s m-(1+beta)"


def axis_label(name: str, quantity: str, units: str, values=()) -> tuple[str, Scaled]:
    """``"name (unit)"`` for an axis of ``values``, and the scaling to draw them with."""
    scaled = scale_for(quantity, units, values)
    return (f"{name} ({scaled.unit})" if scaled.unit else name), scaled


def format_value(value: float, quantity: str, units: str, digits: int = 4,
                 zeros: bool = False) -> str:
    """One value for a person: ``"223.6 µs"`` in SI, ``"6.177"`` in the paper's units
    (``digits`` significant digits; ``nan``, ``inf`` as such). ``zeros`` keeps trailing
    zeros (``31.700 N``), as a measured value's digits are."""
    if not math.isfinite(value):
        return str(value)
    scaled = scale_for(quantity, units, [value]) if units == "si" else Scaled(1.0, "")
    text = f"{value * scaled.factor:{'#' if zeros else ''}.{digits}g}".rstrip(".")
    return f"{text} {scaled.unit}" if scaled.unit else text


def balls_text(values, quantity: str, units: str, digits: int = 4) -> str:
    """The balls' ``values`` of a ``quantity`` in brief, saying which ball is which:
    one value (``25.4 mm``); one ball apart (``25.4 mm, ball 1 of 32.002 mm``); a
    taper (``25.4 mm (ball 1) to 9.585 mm (ball 20)``); else their range (``10 g to
    30 g``)."""
    def value(x):
        return format_value(float(x), quantity, units, digits)
    a = np.asarray(values, dtype=float)
    if np.all(a == a[0]):
        return value(a[0])
    common, counts = np.unique(a, return_counts=True)
    if counts.max() == a.size - 1:
        odd = int(np.flatnonzero(a != common[np.argmax(counts)])[0])
        return f"{value(common[np.argmax(counts)])}, ball {odd + 1} of {value(a[odd])}"
    steps = np.diff(a)
    if np.all(steps >= 0) or np.all(steps <= 0):
        return f"{value(a[0])} (ball 1) to {value(a[-1])} (ball {a.size})"
    return f"{value(a.min())} to {value(a.max())}"


def run_message(sol, units: str) -> str:
    """A solution's message (``chainrun.solver.Solution``) in the run's units: its
    time with a unit in SI (``terminal state reached at t = 1.19308 ms``), as the
    solver writes it in the paper's."""
    if units != "si":
        return sol.message
    return sol.message_with(lambda t: format_value(t, "time", units, 6))


def end_phrase(terminal, ends, units: str) -> str:
    """When the velocities at the end of some runs were taken, for a label: "" where
    every run reached its terminal state (``terminal``, one flag a run: they are final),
    else ``"at t = 1.5 ms"`` where the runs all stopped at one time (``ends``), or
    ``"where each run stopped"``."""
    if all(bool(t) for t in terminal):
        return ""
    times = {float(t) for t in ends}
    if len(times) == 1:
        return f"at t = {format_value(times.pop(), 'time', units)}"
    return "where each run stopped"


def _last_place(spread: float) -> int:
    """The power of ten of the last digit a (finite, non-zero) ``spread`` supports:
    the smallest place whose unit is at least the spread (3e-5 -> -4, 1e-5 -> -5)."""
    spread = abs(spread)
    last = math.floor(math.log10(spread))
    if 10.0 ** last < spread * (1 - 1e-12):
        last += 1
    return last


def format_supported(value: float, spread: float, digits: int = 6) -> str:
    """``value`` with no digit that its ``spread`` does not support.

    A spread of 0 (or NaN: not measured) leaves ``value`` at ``digits`` significant
    digits (``.6g``). Otherwise the last digit kept is the one whose unit is at least
    the spread, so it is uncertain by about one unit (a spread estimates the run's
    error, which can be a little more: ``chainrun.check``): 0.148611 with a spread of 3e-5
    is ``0.1486``, with 0.002 ``0.15`` (zeros kept: they are digits). A value whose
    leading digit the spread does not reach is shown to one digit, marked ``~``; an
    infinite spread supports nothing (``—``).

    Parameters
    ----------
    value, spread : float
    digits : int
        The most significant digits shown.
    """
    if not math.isfinite(value):
        return str(value)
    if math.isnan(spread) or spread == 0.0:
        return f"{value:.{digits}g}"
    if not math.isfinite(spread):
        return "—"
    last = _last_place(spread)
    lead = math.floor(math.log10(abs(value))) if value else last
    if lead - last + 1 >= digits:                    # the spread cuts no digit of .6g
        return f"{value:.{digits}g}"
    if lead < last:
        return f"~{value:.0e}"
    if last <= 0 and 1e-4 <= abs(value) < 1e6:
        return f"{value:.{-last}f}"
    return f"{value:.{lead - last}e}"


def format_digits(value: float, error: float = math.nan, digits: int = 5) -> str:
    """``value`` in plain notation with its trailing zeros, to at most ``digits``
    significant digits and to none that its ``error`` does not support: the last digit
    kept is the one whose unit is at least the error (``format_supported``). 26.0007
    with an error of 0.004 is ``26.00``, to one digit 699 is ``700``. An error of NaN
    or 0 cuts no digit; a value below its error's place is shown to one digit, marked
    ``~``."""
    if not math.isfinite(value):
        return str(value)
    lead = math.floor(math.log10(abs(value))) if value else 0
    last = lead - digits + 1
    if math.isfinite(error) and error > 0.0:
        last = max(last, _last_place(error))
    return _at_place(value, last) if lead >= last else f"~{value:.0e}"


def format_measured(value: float, error: float, quantity: str | None, units: str,
                    digits: int = 5) -> str:
    """A measured ``value`` for a person, in its prefix (``scale_for``; ``quantity``
    None: a pure number), to the digits ``format_digits`` keeps of it and its
    ``error``: 26.0007 µs measured to 4 ns is ``26.00 µs``, to 0.04 ns ``26.001 µs``;
    699 µN to one digit ``700 µN``."""
    if not math.isfinite(value):
        return str(value)
    scaled = scale_for(quantity, units, [value]) if units == "si" else Scaled(1.0, "")
    text = format_digits(value * scaled.factor, error * scaled.factor, digits)
    return f"{text} {scaled.unit}" if scaled.unit else text


_SPEC = re.compile(r"(?P<head>[^.]*)\.(?P<digits>\d+)(?P<kind>[efg%])$")


def _place(error: float) -> int:
    """The power of ten of an (finite, positive) ``error``'s second significant digit,
    once the error is rounded to two digits (0.23 -> -2, 56 -> 0, 0.0996 -> -2)."""
    return math.floor(math.log10(float(f"{error:.2g}"))) - 1


def _at_place(value: float, place: int) -> str:
    """``value`` rounded to the digit of ``10**place``, in plain notation."""
    if not math.isfinite(value):
        return str(value)
    if place < 0:
        text = f"{value:.{-place}f}"
    else:
        step = 10.0 ** place
        text = f"{round(value / step) * step:.0f}"
    return text[1:] if text.startswith("-") and not text.strip("-0.") else text


def format_with_error(value: float, error: float, *others: float) -> tuple[str, ...]:
    """``value`` to the place of its ``error``'s second significant digit, and the error
    to two digits, in one notation (602.71 and 0.23, 0.8405088400 and 0.0000000037,
    55600 and 1700); ``others`` (the ends of a range, say) after them, to that same
    place or to their own second significant digit where that is finer (the small end
    of a range beside a large deviation: 1400 beside 590000, not 0). Without a finite
    error > 0, six significant digits and ""."""
    if not (math.isfinite(error) and error > 0.0):
        return (f"{value:.6g}", "", *(f"{x:.6g}" for x in others))
    place = _place(error)
    return (_at_place(value, place), _at_place(float(f"{error:.2g}"), place),
            *(_at_place(x, _own_place(x, place)) for x in others))


def _own_place(x: float, place: int) -> int:
    """``place``, or the place of ``x``'s second significant digit where that is finer."""
    if not (math.isfinite(x) and x != 0.0):
        return place
    return min(place, math.floor(math.log10(abs(x))) - 1)


def supported_format(fmt: str, value: float, spread: float) -> str:
    """``format(value, fmt)``, with no digit that ``spread`` does not support.

    A fixed (``.4f``), percent (``.1%``), exponent (``.2e``) or general (``.6g``)
    precision is lowered to the digits the spread supports (``format_supported``); a
    spread of 0 or NaN, or a format of another kind, leaves it as it is.
    """
    found = _SPEC.match(fmt)
    if found is None or math.isnan(spread) or spread == 0.0 or not math.isfinite(value):
        return format(value, fmt)
    if not math.isfinite(spread):
        return "—"
    head, digits, kind = found["head"], int(found["digits"]), found["kind"]
    last = _last_place(spread * (100.0 if kind == "%" else 1.0))
    if kind in "f%":
        return format(value, f"{head}.{min(digits, max(0, -last))}{kind}")
    lead = math.floor(math.log10(abs(value))) if value else last
    if kind == "e":
        return format(value, f"{head}.{min(digits, max(0, lead - last))}e")
    text = format_supported(value, spread, digits)
    return f"+{text}" if "+" in head and value >= 0 and not text.startswith("~") else text
