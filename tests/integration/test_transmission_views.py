"""A driven sweep's transmission from Python and from ``chainrun plot OUTDIR``: the same
numbers from a folder, its Dataset and its runs; the curve drawn is the one measured;
runs it cannot be measured on are refused in one line."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from helpers import driven_sweep, simulate_text

import chainrun
from chainrun.cli import main
from chainrun.errors import ChainrunError
from chainrun.plotting import style
from chainrun.plotting.transmission import draw_transmission

SWEEP = driven_sweep("shaken", 10, [0.45, 0.2, 0.3])


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    return simulate_text(tmp_path_factory.mktemp("transmission"), SWEEP)


def test_a_folder_its_dataset_and_a_run_give_the_same_transmission(sweep):
    curve = chainrun.transmission(sweep)
    assert curve.frequency.values.tolist() == [0.2, 0.3, 0.45]        # sorted
    assert curve.run.values.tolist() == [f"left_motion_frequency={f}" for f in (0.2, 0.3, 0.45)]
    assert "run_id" not in curve.attrs and curve.attrs["experiment"] == "shaken"  # of no one run
    assert curve.transmission.dims == ("frequency", "sensor", "harmonic")
    same = chainrun.transmission(chainrun.open_sweep(sweep))
    np.testing.assert_array_equal(same.transmission.values, curve.transmission.values)
    tree = chainrun.simulate(sweep.parent / "experiment.toml")      # the same sweep
    np.testing.assert_array_equal(chainrun.transmission(tree).transmission.values,
                                  curve.transmission.values)
    one = chainrun.transmission(sweep / "left_motion_frequency=0.3.h5")
    np.testing.assert_array_equal(one.amplitude.values,
                                  curve.amplitude.sel(frequency=0.3).values)
    assert one.transmission.attrs["units"] == "1" and one.amplitude.attrs["units"] == "paper units"
    # the default window: the second half of the time after the ramp, whole periods
    last = float(chainrun.open_run(sweep / "left_motion_frequency=0.3.h5").sample[-1])
    assert int(one.periods) == 13 and float(one.window_end) == last
    assert float(one.window_start) == pytest.approx(last - 13 / 0.3)
    # 0.45 lies above the cut-off 2 sqrt(1.5) / (2 pi) = 0.39: the far end gets little
    far = curve.transmission.sel(sensor=10, harmonic=1)
    assert far.sel(frequency=0.45) < 1e-3 * far.sel(frequency=0.2)


def test_every_variable_has_a_short_label_for_plots_and_its_description(sweep):
    curve = chainrun.transmission(sweep)
    for name, var in curve.variables.items():
        label = var.attrs.get("long_name", "")
        assert label and len(label) <= 40 and ":" not in label, (name, label)
    assert curve.transmission.attrs["long_name"] == "transmission"
    assert "reference_force" in curve.transmission.attrs["description"]
    assert curve.frequency.attrs["long_name"] == "drive frequency"


def test_the_figure_draws_the_measured_curve_and_the_bands(sweep):
    curve = chainrun.transmission(sweep)
    with style(colour=True):
        figure = draw_transmission(curve, "shaken")
    axes = figure.axes[0]
    drawn = {a.get_gid(): a for a in axes.get_children() if a.get_gid()}
    for ball in (1, 10):
        x, y = drawn[f"transmission/{ball}"].get_data()
        np.testing.assert_array_equal(x, curve.frequency.values)
        np.testing.assert_array_equal(y, curve.transmission.sel(sensor=ball, harmonic=1))
    assert axes.get_yscale() == "log" and "stop/1" in drawn and "band_edge" in drawn
    # three frequencies, one above the cut-off: points, not a curve drawn through the gap
    assert all(drawn[f"transmission/{ball}"].get_linestyle() == "None" for ball in (1, 10))
    # a ramp of a few periods leaves the start's modes ringing in this lossless line: the
    # points where they outweigh the response at f are drawn hollow, and only those
    for ball in (1, 10):
        loose = ~curve.steady.sel(sensor=ball).values
        if loose.any():
            x, y = drawn[f"not_steady/{ball}"].get_data()
            np.testing.assert_array_equal(x, curve.frequency.values[loose])
        else:
            assert f"not_steady/{ball}" not in drawn
    # above the cut-off the far end gets next to nothing: what is left of the ramp's
    # transient is most of its signal
    assert not curve.steady.sel(sensor=10, frequency=0.45)
    assert curve.steady.sel(sensor=1, frequency=0.45)
    # each sensor in its colour of the run's own sensors view, hollow points or not
    from chainrun.plotting.views import draw_view
    from chainrun.store import read_run

    with style(colour=True):
        own = draw_view(read_run(sweep / "left_motion_frequency=0.2.h5"), "sensors")
    colours = {a.get_gid(): a.get_color() for a in own.axes[0].get_lines() if a.get_gid()}
    assert any((~curve.steady.sel(sensor=ball)).any() for ball in curve.sensor.values[:-1])
    for ball in curve.sensor.values:
        assert drawn[f"transmission/{ball}"].get_color() == colours[f"sensor/{ball}"], ball


@pytest.mark.slow
def test_chainrun_plot_draws_a_frequency_sweeps_transmission(sweep, tmp_path):
    result = CliRunner().invoke(main, ["plot", str(sweep), "--what", "sensors",
                                       "-o", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "transmission.png").stat().st_size > 0
    assert (tmp_path / "transmission.pdf").stat().st_size > 0
    # where a driven run stops its velocities are a phase of its oscillation: no
    # figure of them against the frequency
    assert not (tmp_path / "sweep-final.png").exists()
    assert not (tmp_path / "sweep-runs.png").exists()
    # the sweep's figure alone
    alone = tmp_path / "alone"
    result = CliRunner().invoke(main, ["plot", str(sweep), "--what", "transmission",
                                       "-o", str(alone)])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in alone.iterdir()) == ["transmission.pdf", "transmission.png"]
    result = CliRunner().invoke(main, ["plot", str(sweep), "--what", "ensemble",
                                       "-o", str(alone)])
    assert result.exit_code == 2 and "has no view ensemble (it has transmission)" in \
        result.output, result.output


def test_runs_without_a_sine_or_sensors_are_refused_in_one_line(tmp_path):
    still = chainrun.simulate(chain={"n": 4, "k": 0, "alpha": 1.5, "precompression": 1.0},
                              walls={"left": {}, "right": {}}, solver={"t_end": 5.0},
                              output={"sensors": [2], "sensor_dt": 0.1})
    with pytest.raises(ChainrunError, match="no wall moves by a sine"):
        chainrun.transmission(still)
    blind = chainrun.simulate(chain={"n": 4, "k": 0, "alpha": 1.5, "precompression": 1.0},
                              walls={"left": {"motion": {"amplitude": 1e-6, "frequency": 0.3}},
                                     "right": {}}, solver={"t_end": 5.0})
    with pytest.raises(ChainrunError, match="no force sensors"):
        chainrun.transmission(blind)
    short = chainrun.simulate(chain={"n": 4, "k": 0, "alpha": 1.5, "precompression": 1.0},
                              walls={"left": {"motion": {"amplitude": 1e-6, "frequency": 0.3,
                                                         "ramp": 4.0}}, "right": {}},
                              solver={"t_end": 5.0}, output={"sensors": [2], "sensor_dt": 0.1})
    with pytest.raises(ChainrunError, match="not one whole period"):
        chainrun.transmission(short)
    # 20 harmonics of 0.3 reach 6, beyond 1 / (2 * 0.1) = 5: the frequencies said, and
    # the sampling that would do, 1 / (2 * 20 * 0.3) = 0.08333
    with pytest.raises(ChainrunError, match=r"20 times the drive's frequency 0.3 is above "
                                            r"the sensors' Nyquist frequency 1/\(2 sensor_dt\)"
                                            r" = 5; sample faster \(a sensor_dt below "
                                            r"0.08333\) or fit fewer harmonics"):
        chainrun.transmission(short, harmonics=20, start=0.0)
    from chainrun.errors import ChainrunWarning

    with pytest.warns(ChainrunWarning, match="the wall does not move"):
        still_wall = chainrun.simulate(
            chain={"n": 4, "k": 0, "alpha": 1.5, "precompression": 1.0},
            walls={"left": {"motion": {"amplitude": 0.0, "frequency": 0.3}}, "right": {}},
            solver={"t_end": 5.0}, output={"sensors": [2], "sensor_dt": 0.1})
    with pytest.raises(ChainrunError, match=r"does not move \(walls.left.motion.amplitude is 0\)"):
        chainrun.transmission(still_wall)
