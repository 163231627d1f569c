"""``chainrun spectrum`` and ``chainrun.spectrum``: the real command in a temporary
folder, its file, figure and summary; the same Dataset from Python; errors in one line."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

import chainrun
from chainrun import atomic
from chainrun.cli import main
from chainrun.errors import ConfigError
from chainrun.plotting import style
from chainrun.plotting.spectrum import draw_spectrum
from chainrun.store import read_spectrum

EXAMPLE = Path(__file__).resolve().parents[2] / "configs" / "examples" / "granular-crystal.toml"
#: what differs between two computations of the same spectrum
VARYING = ("format", "format_version", "created", "creator_name", "creator_version")

DIMER = """name = "dimer"
[chain]
n = 16
k = 0
alpha = 1.5
mass = {pattern = [2.0, 1.0]}
precompression = 0.5
[walls.left]
[walls.right]
"""


@pytest.fixture
def cli(tmp_path, monkeypatch):
    """Invoke ``chainrun ARGS`` in an empty temporary working folder."""
    monkeypatch.chdir(tmp_path)

    def invoke(*args):
        return CliRunner().invoke(main, [str(a) for a in args])
    return invoke


def test_the_command_writes_the_spectrum_its_figure_and_a_summary(cli, tmp_path):
    config = tmp_path / "dimer.toml"
    config.write_text(DIMER)  # between two walls, no solver.t_end: nothing is run
    result = cli("spectrum", config)
    assert result.exit_code == 0, result.output
    out = tmp_path / "results" / "dimer" / "spectrum"
    assert sorted(p.name for p in out.iterdir()) == ["run.h5", "run.pdf", "run.png"]
    assert not atomic.leftovers(out, ["run.h5", "run.png", "run.pdf"])
    ds = read_spectrum(out / "run.h5")
    same = chainrun.spectrum(config)
    for key in VARYING:
        ds.attrs.pop(key)
    xr.testing.assert_identical(ds, same)
    # K = 1.5 (0.5)^(1/3), masses 2 and 1: the gap runs from sqrt(2K/2) to sqrt(2K)
    K = 1.5 * 0.5 ** (1 / 3)
    text = result.output
    assert text.startswith("run: N = 16 balls at rest, 16 modes: omega ")
    two_pi = 2 * math.pi
    assert (f"band gap: {math.sqrt(K):#.4g} ... {math.sqrt(2 * K):#.4g} (f "
            f"{math.sqrt(K) / two_pi:#.4g} ... {math.sqrt(2 * K) / two_pi:#.4g})\n") in text
    assert "periodic, 2 balls per cell; pass bands (omega): 0 ... " in text
    assert f"-> {Path('results/dimer/spectrum/run.h5')}, run.png, run.pdf" in text


def test_the_example_in_si(cli, tmp_path):
    result = cli("spectrum", EXAMPLE, "-o", tmp_path / "gc")
    assert result.exit_code == 0, result.output
    ds = read_spectrum(tmp_path / "gc" / "run.h5")
    assert ds.attrs["units"] == "SI" and ds.attrs["period"] == 2
    assert ds.omega.attrs["units"] == "rad/s"
    # short labels for plots' axes, kept by the file; what each is in its description
    for name, var in ds.variables.items():
        label = var.attrs.get("long_name", "")
        assert label and len(label) <= 40 and ":" not in label, (name, label)
    assert ds.shape.attrs["long_name"] == "mode shape"
    assert "largest magnitude 1" in ds.shape.attrs["description"]
    # stated in the units' prefixes, a gap in krad/s
    assert re.search(r"band gap: [\d.]+ krad/s \.\.\. [\d.]+ krad/s \(f [\d.]+ kHz \.\.\. "
                     r"[\d.]+ kHz\)", result.output)
    assert re.search(r"\(f [\d.]+ Hz \.\.\. [\d.]+ kHz\)", result.output)
    # every frequency but an exact 0 to four significant digits, its zeros kept
    numbers = re.findall(r"([\d.]+) k?(?:rad/s|Hz)", result.output)
    assert "0" in numbers and len(numbers) > 10
    for number in numbers:
        assert number == "0" or len(number.replace(".", "").lstrip("0")) == 4, number
    np.testing.assert_allclose(ds.static_force, 5.0, rtol=1e-12)  # walls' contacts too
    assert ds.contact.values.tolist() == list(range(21))


def test_a_sweep_gives_a_file_per_run_and_a_tree(cli, tmp_path):
    config = tmp_path / "dimer.toml"
    config.write_text(DIMER + '[sweep]\n"chain.precompression" = [0.5, 4.0]\n')
    result = cli("spectrum", config, "-o", "out")
    assert result.exit_code == 0, result.output
    names = sorted(p.name for p in (tmp_path / "out").glob("*.h5"))
    assert names == ["precompression=0.5.h5", "precompression=4.0.h5"]
    tree = chainrun.spectrum(config)
    low = tree["precompression=0.5"].to_dataset()
    high = tree["precompression=4.0"].to_dataset()
    # Hertz: K grows as F0^(1/3), so every frequency as F0^(1/6)
    np.testing.assert_allclose(high.omega / low.omega, 8 ** (1 / 6), rtol=1e-12)


def test_a_sweep_of_the_drive_alone_writes_its_one_spectrum_once(cli, tmp_path):
    config = tmp_path / "shaken.toml"
    config.write_text(DIMER + "[walls.left.motion]\namplitude = 1e-4\nfrequency = 0.1\n"
                      "ramp = 10.0\n[solver]\nt_end = 50.0\n"
                      '[sweep]\n"walls.left.motion.frequency" = [0.1, 0.2, 0.3]\n')
    result = cli("spectrum", config, "-o", "out")
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in (tmp_path / "out").glob("*.h5")) == [
        "left_motion_frequency=0.1.h5"]
    for f in (0.2, 0.3):
        assert (f"left_motion_frequency={f}: the same line at rest as "
                f"left_motion_frequency=0.1, the same spectrum") in result.output
    tree = chainrun.spectrum(config)  # (Python: every run's, as its tree)
    np.testing.assert_array_equal(tree["left_motion_frequency=0.3"].to_dataset().omega,
                                  tree["left_motion_frequency=0.1"].to_dataset().omega)


@pytest.mark.parametrize("text, args, message", [
    (DIMER.replace("alpha = 1.5", "alpha = 0.5"), (),
     "dimer.toml: chain.alpha: must be >= 1, got 0.5"),
    # a force on ball 1 that nothing holds: not a static state
    (DIMER.replace("precompression = 0.5",
                   "force = {value = 0.0, impurity = {at = 1, value = 0.5}}"), (),
     "chainrun: error: {config}: ball 1 is not at rest in a static state: the forces on "
     "it add up to 0.5 (largest force on the line 0.5); the spectrum is of a line at rest "
     "(chain.precompression places one)"),
    (DIMER, ("--period", "3"),
     "chainrun: error: {config}: period: the line does not repeat every 3 balls: the mass "
     "of ball 4 differs from ball 1's (counting the balls at rest from 1)"),
])
def test_errors_are_one_line_naming_the_key(cli, tmp_path, text, args, message):
    config = tmp_path / "dimer.toml"
    config.write_text(text)
    result = cli("spectrum", config, *args)
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.output
    assert lines[0].endswith(message.format(config=config)), lines[0]
    assert not (tmp_path / "results" / "dimer" / "spectrum" / "run.h5").exists()


def test_python_errors_name_the_key():
    with pytest.raises(ConfigError, match=r"^<spectrum>: chain.k: must be >= 0, got -1$"):
        chainrun.spectrum(chain={"n": 3, "k": -1, "alpha": 1.5})


def test_the_figure_draws_what_the_file_holds():
    ds = chainrun.spectrum(chain={"n": 16, "k": 0, "alpha": 1.5,
                                  "mass": {"pattern": [2.0, 1.0]}, "precompression": 0.5},
                           walls={"left": {}, "right": {}})
    with style():
        figure = draw_spectrum(ds)
    modes, bands = figure.axes
    (hertz,) = bands.child_axes
    (line,) = [a for a in modes.get_lines() if a.get_gid() == "omega"]
    np.testing.assert_array_equal(line.get_xdata(), ds.mode.values)
    np.testing.assert_array_equal(line.get_ydata(), ds.omega.values)  # paper units: as is
    for branch in (1, 2):
        (curve,) = [a for a in bands.get_lines() if a.get_gid() == f"dispersion/{branch}"]
        np.testing.assert_array_equal(curve.get_xdata(), ds.q.values)
        np.testing.assert_array_equal(curve.get_ydata(), ds.dispersion.sel(branch=branch))
    gaps = [p for p in bands.patches if p.get_gid() == "gap/1"]
    assert len(gaps) == 1
    assert modes.get_ylabel() == r"angular frequency $\omega$ (paper units)"
    assert hertz.get_gid() == "frequency" and "paper units" in hertz.get_ylabel()


def test_an_si_figure_gives_the_frequency_in_hertz_beside_omega():
    ds = chainrun.spectrum(units="si", chain={"n": 12, "k": 0, "diameter": 0.008,
                                              "material": "stainless_steel",
                                              "precompression": 5.0},
                           walls={"left": {"material": "steel"}, "right": {"material": "steel"}})
    with style():
        figure = draw_spectrum(ds)
    modes, bands = figure.axes
    (hertz,) = bands.child_axes
    assert modes.get_ylabel() == r"angular frequency $\omega$ (krad/s)"
    assert hertz.get_ylabel() == r"frequency $f = \omega / 2\pi$ (kHz)"
    # titled by what the line is, read back from the experiment the spectrum keeps
    title = figure.get_suptitle()
    assert "N = 12 stainless steel spheres of 8 mm" in title and "precompressed 5 N" in title
    top = float(ds.omega.max())
    to_hertz = hertz._functions[0]
    assert to_hertz(top / 1e3) == pytest.approx(top / (2 * np.pi) / 1e3, rel=1e-12)


def test_help_has_examples(cli):
    result = cli("spectrum", "--help")
    assert result.exit_code == 0
    examples = result.output.split("Examples:\n", 1)[1]
    assert re.search(r"^\s+chainrun spectrum \S+", examples, re.MULTILINE)
