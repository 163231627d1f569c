"""Inputs that are valid but probably not meant: warnings, not errors.

A length typed in millimetres in an SI file (``diameter = 20``) is a valid line of
20 m spheres of 33,000 t each, and it runs; so does a wall 5 m away, or an overlap deeper
than a bead. Such a run ends well and answers a question nobody asked, so the command
says so before it runs (``doubts``), naming the key, with what the value means and what
was probably meant. Lengths are judged on lines of spheres in SI units only: the
paper's units and lines of masses and stiffnesses have no scale to judge them against.
So is an impact speed that would press two beads together by more than a hundredth of
their diameter (``speed = 300`` for 0.3 m/s: 2.4 mm of 25.4 mm steel balls, at a
mean pressure of 14 GPa). A moving wall is judged in any units: an amplitude of 0 (the
wall does not move), and force sensors too slow to follow it.
"""

from __future__ import annotations

import numpy as np

from chainrun.units import format_value

__all__ = ["doubts", "LARGEST_DIAMETER", "FARTHEST_GAP", "DEEPEST_OVERLAP",
           "DEEPEST_IMPACT", "SAMPLES_PER_PERIOD"]

#: Spheres wider than this (m) are reported: a diameter in millimetres typed as metres.
LARGEST_DIAMETER = 1.0
#: Gaps wider than this many of the largest diameter are reported (a gap typed in mm).
FARTHEST_GAP = 10.0
#: Overlaps deeper than this share of the smaller diameter are reported: Hertz's law is
#: for compressions small against the spheres (and one of a whole diameter is none).
DEEPEST_OVERLAP = 0.1
#: Impacts that would press two spheres together by more than this share of the smaller
#: diameter are reported: far past where Hertz's law holds, and where any metal yields
#: (steel beads at about 15 m/s; a speed typed in mm/s as m/s reaches it).
DEEPEST_IMPACT = 0.01
#: Force sensors that sample a moving wall's sine this many times a period or fewer are
#: reported: ``chainrun.transmission`` fits its frequency and two harmonics, the third
#: below the sensors' Nyquist frequency (more than 6 samples a period).
SAMPLES_PER_PERIOD = 6


def doubts(specs) -> list[str]:
    """One line per doubtful value of the runs ``specs`` (``RunSpec``), each said once
    however many runs share it."""
    seen: dict[str, None] = {}
    for spec in specs:
        if spec.is_paper:
            continue
        found = _drive_doubts(spec) + (_line_doubts(spec.line) if spec.units == "si" else [])
        for line in found:
            seen.setdefault(line)
    return list(seen)


def _drive_doubts(spec) -> list[str]:
    """A moving wall that does not move, and sensors too slow to follow one."""
    out = []
    for side, wall in (("left", spec.line.left), ("right", spec.line.right)):
        if wall is None or wall.motion is None:
            continue
        drive = wall.motion
        if drive.size == 0.0:
            out.append(f"walls.{side}.motion.amplitude: 0, so the wall does not move and "
                       f"the line stays at rest")
            continue
        if not spec.sensors or not spec.sensor_dt or drive.times is not None:
            continue
        f = max(s.frequency for s in drive.sines)
        per = 1.0 / (f * spec.sensor_dt)
        if per <= SAMPLES_PER_PERIOD:
            def fmt(x, q):
                return format_value(float(x), q, spec.units)
            out.append(f"output.sensor_dt: {fmt(spec.sensor_dt, 'time')} samples the "
                       f"{side} wall's {fmt(f, 'frequency')} {per:.2g} times a period; "
                       f"chainrun.transmission fits it and two harmonics, which needs "
                       f"more than {SAMPLES_PER_PERIOD} (a sensor_dt below "
                       f"{fmt(1.0 / (SAMPLES_PER_PERIOD * f), 'time')})")
    return out


def _length(x: float) -> str:
    return format_value(float(x), "diameter", "si")


def _impact_depth(line, j: int) -> float:
    """The greatest compression of contact j (0-based) were its two balls to collide
    alone at their initial approach speed w: the two-body energy balance
    mu w^2 / 2 = kappa c^(alpha+1) / (alpha+1), mu the reduced mass; 0 if they part."""
    w = float(line.velocity[j] - line.velocity[j + 1])
    if not w > 0.0:
        return 0.0
    mu = float(line.mass[j] * line.mass[j + 1] / (line.mass[j] + line.mass[j + 1]))
    a = float(line.alpha[j])
    return float(((a + 1.0) * mu * w * w / (2.0 * line.stiffness[j])) ** (1.0 / (a + 1.0)))


def _line_doubts(line) -> list[str]:
    if line.diameter is None:
        return []
    d = np.asarray(line.diameter, dtype=float)
    out = []
    if line.n > 1:
        depths = [(_impact_depth(line, j) / min(d[j], d[j + 1]), j) for j in range(line.n - 1)]
        ratio, j = max(depths)
        if ratio > DEEPEST_IMPACT:
            w = float(line.velocity[j] - line.velocity[j + 1])
            out.append(f"chain.speed: balls {j + 1} and {j + 2} meet at {w:g} m/s and would "
                       f"press together by {_length(ratio * min(d[j], d[j + 1]))}, "
                       f"{100 * ratio:.2g}% of their diameter, far past where Hertz's law holds "
                       f"and real beads yield; speeds in an SI file are in m/s ({w:g} mm/s "
                       f"would be {w / 1000:g})")
    i = int(np.argmax(d))
    if d[i] > LARGEST_DIAMETER:
        out.append(f"chain.diameter: spheres of {_length(d[i])} (ball {i + 1}: "
                   f"{float(line.mass[i]):.3g} kg); lengths in an SI file are in metres "
                   f"({d[i]:g} mm would be {d[i] / 1000:g})")
    largest = float(d.max())
    gaps = [(f"chain.gap (contact {j + 1}, balls {j + 1}-{j + 2})", float(g),
             float(min(d[j], d[j + 1]))) for j, g in enumerate(np.asarray(line.gap))]
    for side, wall, end in (("left", line.left, 0), ("right", line.right, -1)):
        if wall is not None:
            gaps.append((f"walls.{side}.gap", float(wall.gap), float(d[end])))
    far = [(key, g) for key, g, _ in gaps if g > FARTHEST_GAP * largest]
    if far:
        key, g = max(far, key=lambda kg: kg[1])
        out.append(f"{key}: a gap of {_length(g)}, {g / largest:.3g} diameters"
                   + (f" (and {len(far) - 1} more)" if len(far) > 1 else "")
                   + f"; lengths in an SI file are in metres ({g:g} mm would be "
                     f"{g / 1000:g})")
    deep = [(key, -g, small) for key, g, small in gaps if -g > DEEPEST_OVERLAP * small]
    if deep:
        key, overlap, small = max(deep, key=lambda kgs: kgs[1] / kgs[2])
        through = overlap >= small
        ratio = overlap / small
        share = f"{ratio:.3g} times" if ratio >= 1.0 else f"{ratio:.2g} of"
        out.append(f"{key}: an overlap of {_length(overlap)}, {share} the diameter; "
                   + ("the spheres would be inside one another, which Hertz's law does "
                      "not describe" if through else
                      "Hertz's law holds for compressions small against the spheres")
                   + (f" (and {len(deep) - 1} more)" if len(deep) > 1 else ""))
    return out
