"""Inputs that are valid but probably not meant: warnings, not errors.

A length typed in millimetres in an SI file (``diameter = 20``) is a valid line of
20 m spheres of 33,000 t each, and it runs; so does a wall 5 m away, or an overlap deeper
than a bead. Such a run ends well and answers a question nobody asked, so the command
says so before it runs (``doubts``), naming the key, with what the value means and what
was probably meant. Only lines of spheres in SI units are judged: the paper's units
and lines of masses and stiffnesses have no scale to judge a length against.
"""

from __future__ import annotations

import numpy as np

from chainrun.units import format_value

__all__ = ["doubts", "LARGEST_DIAMETER", "FARTHEST_GAP", "DEEPEST_OVERLAP"]

#: Spheres wider than this (m) are reported: a diameter in millimetres typed as metres.
LARGEST_DIAMETER = 1.0
#: Gaps wider than this many of the largest diameter are reported (a gap typed in mm).
FARTHEST_GAP = 10.0
#: Overlaps deeper than this share of the smaller diameter are reported: Hertz's law is
#: for compressions small against the spheres (and one of a whole diameter is none).
DEEPEST_OVERLAP = 0.1


def doubts(specs) -> list[str]:
    """One line per doubtful value of the runs ``specs`` (``RunSpec``), each said once
    however many runs share it."""
    seen: dict[str, None] = {}
    for spec in specs:
        if spec.units != "si":
            continue
        for line in _line_doubts(spec.line):
            seen.setdefault(line)
    return list(seen)


def _length(x: float) -> str:
    return format_value(float(x), "diameter", "si")


def _line_doubts(line) -> list[str]:
    if line.diameter is None:
        return []
    d = np.asarray(line.diameter, dtype=float)
    out = []
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
