"""The line in brief that ``chainrun info`` prints (``chainrun.analysis.summary
.describe_line``), from an experiment file's line as it is checked, without running it."""

from __future__ import annotations

from chainrun.analysis.summary import describe_line
from chainrun.config import parse_experiment

DIMER = """name = "dimer"
units = "si"
[chain]
n = 6
k = 0
diameter = 0.019
material = {{pattern = {pattern}}}
precompression = 10.0
[walls.left]
material = "steel"
[walls.right]
material = "steel"
"""


def line_of(text: str):
    (spec,) = parse_experiment(text, "toml", to_run=False).runs(to_run=False)
    return spec.line, spec.units


def test_materials_are_named_in_the_lines_order():
    line, units = line_of(DIMER.format(pattern='["steel", "aluminium"]'))
    assert describe_line(line, units).startswith("steel, aluminium spheres of 19 mm;")
    line, units = line_of(DIMER.format(pattern='["aluminium", "steel"]'))
    assert describe_line(line, units).startswith("aluminium, steel spheres of 19 mm;")
