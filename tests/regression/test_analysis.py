"""Tests of the analysis: derived quantities, the paper's printed values, stored references.

Three kinds of check (docs/design.md, Tests):

1. the measurement functions of ``chainrun.analysis.derived`` and the formulas of
   ``nesterenko`` on inputs with known answers;
2. a fast subset of the paper's artefacts, built end to end (simulate -> analyze) in a
   temporary folder, against the numbers the paper prints, at the printed precision,
   and against chainrun's own values at higher precision, stored with the settings that
   produced them in ``tests/data/analysis_reference.json``;
3. the whole comparison table, built from the stored values of every artefact: every
   printed number is compared, and every disagreement carries an explanation.

The heavy artefacts (dense snapshots: sec5a, sec5b, fig10, fig11, sec5c) run only in
``make figures``; their stored values still feed check 3.

Regenerate the reference after a deliberate change with::

    make figures
    PYTHONPATH=tests .venv/bin/python tests/regression/test_analysis.py --update results
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from chainrun import artefacts
from chainrun.analysis import analyze, derived, nesterenko
from chainrun.analysis.paper import PRINTED, agrees, parse, render_note, tolerance
from chainrun.solver import Line, simulate
from chainrun.store import AnalysisData, read_analysis, read_run, write_analysis

from helpers import FAST, ROOT

REFERENCE = ROOT / "tests" / "data" / "analysis_reference.json"

#: Printed numbers that differ from chainrun's at the printed precision; each carries an
#: explanation in chainrun/analysis/paper.py (checked below).
KNOWN_DISAGREEMENTS = {
    "abstract.hertz.fit_a", "abstract.hertz.fit_b", "3.fig1.rebound", "3.fig2.slope",
    "4a.rebound_share", "4a.wave_share", "4d.xi0", "5a.kinetic_min", "5a.fit_a", "5a.fit_b",
    "5a.ejected_2", "5a.ejected_3", "5a.line_length", "5a.five_v3", "5b.momentum",
    "5c.K2.speed_1", "5c.K2.speed_2", "5c.K3.speed_1", "5c.K3.pseudo_second_1",
    "5c.K3.pseudo_second_2", "5c.K4.displacement_1", "table1.v2_K4", "table1.v3_K4",
}

#: One table of tolerances for chainrun's own values against the stored reference.
TOL = {"rel": 1e-6, "abs": 1e-10}


@pytest.fixture(scope="module")
def reference():
    return json.loads(REFERENCE.read_text())


# ------------------------------------------------------------------ 1. measurements
def test_refined_peaks_of_a_parabola():
    t = np.arange(0.0, 10.0, 0.1)
    y = 2.0 - (t - 4.237) ** 2
    times, values = derived.refined_peaks(t, y, 0.0)
    assert times == pytest.approx([4.237], abs=1e-12)
    assert values == pytest.approx([2.0], abs=1e-12)


def test_refined_peaks_of_pulses():
    t = np.arange(0.0, 60.0, 0.1)
    y = np.exp(-((t - 10.03) / 2) ** 2) + 0.5 * np.exp(-((t - 30.71) / 2) ** 2)
    times, values = derived.refined_peaks(t, y, 0.1)
    assert times == pytest.approx([10.03, 30.71], abs=2e-4)
    assert values == pytest.approx([1.0, 0.5], abs=2e-4)


def test_exponential_and_power_fits_are_exact_on_exact_data():
    n = np.arange(2, 16)
    a, b = derived.exponential_fit(n, -0.084 * np.exp(-0.55 * n))
    assert (a, b) == (pytest.approx(0.084, rel=1e-12), pytest.approx(0.55, rel=1e-12))
    m = np.arange(100.0, 200.0)
    c = derived.power_series_fit(m, -0.159 + 0.13 * m ** (-2 / 3) - 0.14 / m, (2 / 3, 1))
    np.testing.assert_allclose(c, [-0.159, 0.13, -0.14], rtol=1e-9)
    assert derived.loglog_slope(m, 3 * m**-0.75) == pytest.approx(-0.75, rel=1e-12)
    assert derived.polynomial_extrapolation([0.1, 0.2], [1.2, 1.4]) == pytest.approx(1.0)


def test_rebound_shares_and_counts():
    v = np.array([-0.2, -0.05, -0.005, 0.0, 0.3, 0.9])
    ones = np.ones(v.size)
    assert derived.count_significant(v, -1, 1.0) == 2
    assert derived.count_significant(v, +1, 1.0) == 2
    assert derived.rebound_energy_share(v, ones, 0.5) == pytest.approx(0.04 + 0.0025 + 0.000025)
    assert derived.rebound_energy_share(v, ones, 1.0) == pytest.approx(
        (0.04 + 0.0025 + 0.000025) / 2)
    assert derived.rebound_momentum(v, ones) == pytest.approx(-0.255)


def test_rebound_shares_weigh_the_lines_masses():
    v = np.array([-0.2, -0.1, 0.3])
    mass = np.array([3.0, 0.5, 2.0])
    # 0.5 (3 x 0.04 + 0.5 x 0.01) of an impact energy of 0.25
    assert derived.rebound_energy_share(v, mass, 0.25) == pytest.approx(0.25)
    assert derived.rebound_momentum(v, mass) == pytest.approx(-0.65)
    assert derived.count_significant(v, -1, 20.0) == 0   # 1% of 20 is 0.2


def test_solitary_wave_of_a_line_in_its_own_units():
    """A Hertz line of masses 2 and stiffnesses 3 struck at 0.5 is the paper's line in
    its own scales (``Line.scales``): its solitary wave's energies, momentum, force,
    speed and displacement are the paper's in those scales. Measured with unit masses
    and stiffnesses, its energies and force would be off by factors of 2 and 3."""
    n = 100
    line = Line.make(n, mass=2.0, stiffness=3.0, alpha=1.5, speed=0.5)
    sc = line.scales()
    assert (sc.mass, sc.velocity) == (2.0, 0.5)
    t = np.arange(1101) * 0.1
    paper = derived.solitary_wave(simulate(Line.paper(n, 1, 1.5), t), (40.0, 80.0), (30, 80))
    wave = derived.solitary_wave(simulate(line, t * sc.time),
                                 (40.0 * sc.time, 80.0 * sc.time), (30, 80))
    for name, unit in (("energy", sc.energy), ("kinetic_mean", sc.energy),
                       ("potential_mean", sc.energy), ("momentum", sc.mass * sc.velocity),
                       ("max_force", sc.force), ("max_velocity", sc.velocity),
                       ("speed", 1.0 / sc.time), ("displacement", sc.length),
                       ("width", 1.0)):
        assert getattr(wave, name) == pytest.approx(getattr(paper, name) * unit, rel=1e-8), \
            name


def test_position_at_separation_is_exact_for_free_flight(built):
    # every ball of Fig 1's line moves freely after its last separation
    (item,) = [i for i in built("fig01").inputs if i["kind"] == "run"]
    run = read_run(item["file"])
    sep = derived.position_at_separation(run)
    t = np.asarray(run.times)
    x = np.asarray(run.positions)
    for ball in range(run.n):
        after = t > run.separation_time[ball]
        assert np.allclose(x[after, ball] - run.final_velocity[ball]
                           * (t[after] - run.separation_time[ball]), sep[ball], atol=1e-10)


def test_nesterenko_formulas_from_their_integrals():
    wave = nesterenko.from_displacement(1.354)
    s = np.linspace(0.0, wave.width, 200001)
    ds = s[1] - s[0]
    strain = wave.strain(s)
    assert np.trapezoid(strain, dx=ds) == pytest.approx(1.354, rel=1e-9)
    assert wave.speed**2 == pytest.approx(0.8 * np.sqrt(wave.amplitude), rel=1e-14)
    assert wave.velocity(s).max() == pytest.approx(wave.max_velocity, rel=1e-9)
    assert wave.force(s).max() == pytest.approx(wave.max_force, rel=1e-9)
    # momentum and kinetic energy: sums over balls -> integrals over n
    assert np.trapezoid(wave.velocity(s), dx=ds) == pytest.approx(wave.momentum, rel=1e-9)
    assert np.trapezoid(0.5 * wave.velocity(s) ** 2, dx=ds) == pytest.approx(
        wave.kinetic_energy, rel=1e-9)
    # potential energy consistent with (5.1), in the strain e = -dx/dn:
    # int (2/5) e^(5/2) + (1/24) e^(3/2) e''
    e2 = np.gradient(np.gradient(strain, ds), ds)
    potential = np.trapezoid(0.4 * strain**2.5 + strain**1.5 * e2 / 24, dx=ds)
    assert potential == pytest.approx(wave.potential_energy, rel=1e-5)


@pytest.mark.parametrize(("attribute", "text"), [
    ("amplitude", "0.727"), ("speed", "0.826"), ("max_velocity", "0.600"),
    ("max_force", "0.558"), ("kinetic_energy", "0.245"), ("potential_energy", "0.196"),
])
def test_nesterenko_printed_values(attribute, text):
    wave = nesterenko.from_displacement(1.354)
    assert abs(getattr(wave, attribute) - float(text)) <= tolerance(text)


def test_nesterenko_speed_change_below_two_percent():
    assert 0.0 < nesterenko.velocity_change_from_force_law() < 0.02


# ------------------------------------------------------------------- paper catalogue
def test_parse_and_tolerance():
    assert parse("0.841") == (0.841, 3)
    assert parse("96.2%") == (96.2, 1)
    assert parse("1/4") == (0.25, None)
    assert parse("five") == (5.0, 0)
    assert parse("about 0.003") == (0.003, 3)
    assert parse("roughly half") == (0.5, 1)
    assert tolerance("-0.0711") == pytest.approx(5e-5)
    assert tolerance("13.5") == pytest.approx(0.05)
    assert tolerance("7/24") == 0.0


def test_catalogue_is_consistent():
    keys = [p.key for p in PRINTED]
    assert len(keys) == len(set(keys))
    names = {a.name for a in artefacts.ARTEFACTS}
    for p in PRINTED:
        assert p.source.split("/")[0] in names, p.key
        assert p.rule in ("printed", "exact", "between", "below"), p.key
        assert p.transform in ("", "abs", "neg"), p.key
        if p.rule in ("printed", "exact"):
            parse(p.text)            # every printed text parses
    assert KNOWN_DISAGREEMENTS <= set(keys)
    for key in KNOWN_DISAGREEMENTS:
        assert next(p for p in PRINTED if p.key == key).note, f"{key} needs an explanation"


def test_notes_render():
    values = {"fig09": {"ejected_2": 0.14860046}}
    assert render_note("is {fig09/ejected_2:.4f}.", values) == "is 0.1486."
    assert render_note("{fig09/ejected_2}", values) == "0.1486"


# ------------------------------------------------- 2. the fast subset, end to end
FAST_PRINTED = [p for p in PRINTED if p.source.split("/")[0] in FAST]


@pytest.mark.parametrize("entry", FAST_PRINTED, ids=[p.key for p in FAST_PRINTED])
def test_printed_value(built, entry):
    artefact, _, key = entry.source.partition("/")
    value = built(artefact).values[key]
    value = {"": value, "abs": abs(value), "neg": -value}[entry.transform]
    expected = entry.key not in KNOWN_DISAGREEMENTS
    assert agrees(entry, value) == expected, (
        f"{entry.key}: computed {value:.6g}, paper prints {entry.text} "
        f"({'should agree' if expected else 'known to differ; see its note'})")


@pytest.mark.parametrize("name", FAST)
def test_own_values_against_reference(built, reference, name):
    data = built(name)
    stored = reference["artefacts"][name]
    assert data.settings == stored["settings"]
    assert sorted(data.values) == sorted(stored["values"])
    for key, value in stored["values"].items():
        assert data.values[key] == pytest.approx(value, rel=TOL["rel"], abs=TOL["abs"]), key
    # the runs that produced the reference: same configs (else regenerate it)
    got = [i for i in data.inputs if i["kind"] == "run"]
    assert [r["name"] for r in stored["runs"]] == [i["name"] for i in got]
    for item, run in zip(got, stored["runs"]):
        assert read_run(item["file"]).parameters["config_hash"] == run["config_hash"], (
            f"{item['name']}: its config changed; regenerate {REFERENCE.name}")


def test_inputs_are_hashed(built):
    data = built("fig05")
    (run,) = [i for i in data.inputs if i["kind"] == "run"]
    assert run["name"] == "fig05/run"
    from chainrun.store import file_sha256

    assert run["sha256"] == file_sha256(run["file"])
    assert len(run["sha256"]) == 64


def test_fig03_snapshots_are_the_loss_of_contact_times(built):
    data = built("fig03")
    for i, ball in enumerate((10, 20, 30, 40)):
        assert data.values[f"snapshot_{i}_last_free"] == ball
        lag = data.values[f"snapshot_{i}_time"] - data.values[f"loss_time_{ball}"]
        assert 0.0 <= lag < 2e-6


# ------------------------------------------ 3. the whole comparison from stored values
@pytest.fixture(scope="module")
def comparison(reference, tmp_path_factory):
    """The comparison table recomputed from the stored values of every artefact."""
    results = tmp_path_factory.mktemp("comparison")
    for name, stored in reference["artefacts"].items():
        if name == "paper-comparison":
            continue
        path = artefacts.analysis_path(name, results)
        path.parent.mkdir(parents=True, exist_ok=True)
        write_analysis(path, AnalysisData(
            name=name, title="", values=stored["values"], descriptions={}, arrays={},
            attrs={}, settings=stored["settings"], inputs=[]))
    return read_analysis(analyze("paper-comparison", results=results))


def test_comparison_covers_every_printed_number(comparison):
    assert list(comparison.arrays["table/key"]) == [p.key for p in PRINTED]
    assert comparison.values["rows"] == len(PRINTED)


def test_every_disagreement_is_explained(comparison):
    keys = comparison.arrays["table/key"]
    ok = comparison.arrays["table/agrees"]
    notes = comparison.arrays["table/note"]
    assert set(keys[~ok]) == KNOWN_DISAGREEMENTS
    assert all(notes[~ok]), "a disagreement without a note"
    assert comparison.values["unexplained"] == 0
    assert comparison.values["agreeing"] == len(PRINTED) - len(KNOWN_DISAGREEMENTS)


def test_comparison_notes_carry_computed_values(comparison):
    keys = list(comparison.arrays["table/key"])
    note = comparison.arrays["table/note"][keys.index("5a.ejected_2")]
    assert "0.14860" in note and "{" not in note


# ----------------------------------------------------------------- the reference file
def update_reference(results: Path) -> None:
    """Store the values and settings of every analysis file under ``results``."""
    out = {"generated_from": "make figures (configs/*.toml as committed)",
           "tolerance": TOL, "artefacts": {}}
    for artefact in artefacts.ARTEFACTS:
        data = read_analysis(artefacts.analysis_path(artefact.name, results))
        runs = []
        for item in data.inputs:
            if item["kind"] != "run":
                continue
            run = read_run(item["file"])
            p = run.parameters
            runs.append(dict(name=item["name"], n=p["n"], k=p["k"], alpha=p["alpha"],
                             rtol=p["rtol"], t_end=p["t_end"], config_hash=p["config_hash"]))
        out["artefacts"][artefact.name] = dict(
            settings=data.settings, runs=runs,
            values={k: float(v) for k, v in sorted(data.values.items())})
    REFERENCE.parent.mkdir(parents=True, exist_ok=True)
    REFERENCE.write_text(json.dumps(out, indent=1, sort_keys=False) + "\n")


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] != "--update":
        sys.exit("usage: PYTHONPATH=tests python tests/regression/test_analysis.py --update "
                 "RESULTS")
    update_reference(Path(sys.argv[2]))
    print(f"wrote {REFERENCE}")
