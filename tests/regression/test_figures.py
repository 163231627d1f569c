"""Tests of the figures and tables: the registry, the plotted data, reproducible files.

The registry (``chainrun.artefacts``) is checked against the configs, the analysis
recipes, the plotting modules, ``chainrun plot --list`` and the make rules. Figures are
tested by the data on their axes (each line carries the gid of the series it was drawn
from), never by pixels; files are tested for identical bytes on a second rendering.
"""

from __future__ import annotations

import hashlib
import importlib
import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from chainrun import artefacts
from chainrun.analysis import recipe
from chainrun.cli import main
from chainrun.config import load_experiment

from helpers import FAST, ROOT

FIGURES = [a.name for a in artefacts.ARTEFACTS if a.kind == "figure"]
FAST_FIGURES = [name for name in FIGURES if name in FAST]


@pytest.fixture(scope="session")
def analysis(built):
    """``analysis(name)``: a fast artefact's analysis, built once per test process."""
    return built


@pytest.fixture(scope="session")
def results(built):
    return built.results


# ----------------------------------------------------------------------- the registry
def test_registry_has_every_figure_and_table_of_the_paper():
    assert FIGURES == [f"fig{i:02d}" for i in range(1, 14)]
    names = [a.name for a in artefacts.ARTEFACTS]
    assert "table1" in names and names[-1] == "paper-comparison"
    outputs = {o for a in artefacts.ARTEFACTS for o in a.outputs}
    for i in range(1, 14):
        assert {f"figures/fig{i:02d}.png", f"figures/fig{i:02d}.pdf"} <= outputs
    assert {"tables/table1.md", "tables/table1.csv", "paper-comparison.csv",
            "paper-comparison.md"} <= outputs


def test_every_artefact_has_its_configs_recipe_and_module():
    names = [a.name for a in artefacts.ARTEFACTS]
    for position, a in enumerate(artefacts.ARTEFACTS):
        assert a.kind in artefacts.KINDS
        for experiment in a.experiments:
            spec = load_experiment(ROOT / "configs" / f"{experiment}.toml")
            assert spec.name == experiment
        for need in a.needs:   # analyses needed come earlier: the order builds
            assert need in names[:position], (a.name, need)
        assert callable(recipe(a))
        if a.plot is not None:
            module = importlib.import_module(f"chainrun.plotting.{a.plot}")
            assert hasattr(module, "draw" if a.kind == "figure" else "write")
        else:
            assert a.outputs == ()


def test_every_paper_config_is_used():
    used = set(artefacts.experiments())
    for path in (ROOT / "configs").glob("*.toml"):
        if path.stem.startswith(("fig", "sec", "table")):
            assert path.stem in used, f"{path.name} is not read by any artefact"


def test_plot_list_shows_the_registry():
    runner = CliRunner()
    text = runner.invoke(main, ["plot", "--list"])
    assert text.exit_code == 0, text.output
    for a in artefacts.ARTEFACTS:
        assert a.name in text.output
    listed = runner.invoke(main, ["plot", "--list", "--format", "json"])
    rows = json.loads(listed.output)
    assert [r["name"] for r in rows] == [a.name for a in artefacts.ALL]
    make = runner.invoke(main, ["plot", "--list", "--format", "make"])
    assert make.output == artefacts.make_rules()


def test_make_rules_tie_each_output_to_its_inputs():
    rules = artefacts.make_rules(results="R")
    for a in artefacts.ARTEFACTS:
        line = next(l for l in rules.splitlines() if l.startswith(f"R/analysis/{a.name}.h5:"))
        for e in a.experiments:
            assert f"R/runs/{e}/index.h5" in line
        for n in a.needs:
            assert f"R/analysis/{n}.h5" in line
        assert f"chainrun/analysis/{a.analysis.split(':')[0]}.py" in line
        if a.plot:
            outs = " ".join(f"R/{o}" for o in a.outputs)
            assert f"{outs} &: R/analysis/{a.name}.h5 chainrun/plotting/{a.plot}.py" in rules
    makefile = (ROOT / "Makefile").read_text()
    assert "plot --list --format make" in makefile


def test_cli_errors_are_one_line(tmp_path):
    runner = CliRunner()
    r = runner.invoke(main, ["analyze", "fig99", "--results", str(tmp_path)])
    assert r.exit_code == 2 and "no artefact 'fig99'" in r.output
    r = runner.invoke(main, ["analyze", "fig01", "--results", str(tmp_path)])
    assert r.exit_code == 2 and "chainrun simulate configs/fig01.toml" in r.output
    r = runner.invoke(main, ["plot", "fig01", "--results", str(tmp_path)])
    assert r.exit_code == 2 and "chainrun analyze fig01" in r.output
    r = runner.invoke(main, ["plot", "sec5a", "--results", str(tmp_path)])
    assert r.exit_code == 2 and "only feeds the comparison" in r.output


def test_style_is_shipped_and_reproducible():
    from chainrun.plotting import STYLE

    text = STYLE.read_text()
    assert "svg.hashsalt" in text and "pdf.fonttype" in text
    import matplotlib

    params = matplotlib.rc_params_from_file(STYLE, use_default_template=False)
    assert params["svg.hashsalt"] == "chainrun" and params["pdf.fonttype"] == 42


# ---------------------------------------------------------------- the plotted data
def lines_by_gid(figure):
    return {line.get_gid(): line for ax in figure.axes for line in ax.get_lines()
            if line.get_gid()}


@pytest.mark.parametrize("name", FAST_FIGURES)
def test_axes_show_exactly_the_analysis_series(analysis, name):
    from chainrun.plotting import draw, style

    data = analysis(name)
    with style():
        figure = draw(name, data)
    lines = lines_by_gid(figure)
    series = [f"series/{s}" for s in data.children("series")]
    assert sorted(lines) == sorted(series)
    for gid, line in lines.items():
        np.testing.assert_array_equal(line.get_xdata(), data.arrays[f"{gid}/x"])
        np.testing.assert_array_equal(line.get_ydata(), data.arrays[f"{gid}/y"])
    ax = figure.axes[0]
    assert ax.get_xlabel() and ax.get_ylabel()


@pytest.mark.parametrize(("name", "xscale", "yscale"), [
    ("fig02", "log", "log"), ("fig09", "linear", "log"), ("fig12", "linear", "log"),
    ("fig05", "linear", "linear"), ("fig07", "linear", "linear"),
])
def test_axes_scales_follow_the_paper(analysis, name, xscale, yscale):
    from chainrun.plotting import draw, style

    with style():
        ax = draw(name, analysis(name)).axes[0]
    assert (ax.get_xscale(), ax.get_yscale()) == (xscale, yscale)


def test_fig01_is_displacement_shifted_by_n(analysis, results):
    data = analysis("fig01")
    from chainrun.store import read_run

    (item,) = [i for i in data.inputs if i["kind"] == "run"]
    run = read_run(item["file"])
    x = np.asarray(run.positions)
    for n in range(1, 8):
        np.testing.assert_array_equal(data.arrays[f"series/n={n}/y"], x[:, n - 1] + n)
    guide = data.arrays["series/slope-1/y"] - data.arrays["series/slope-1/x"]
    np.testing.assert_array_equal(guide, 1.0)


def test_fig02_is_minus_the_rebound_velocities(analysis):
    data = analysis("fig02")
    y = data.arrays["series/rebound/y"]
    assert np.all(y > 0) and len(y) == data.values["rebound_count"]
    slope = np.diff(np.log(data.arrays["series/slope/y"])) / np.diff(
        np.log(data.arrays["series/slope/x"]))
    assert slope == pytest.approx([-0.75])


def test_fig05_theory_curve_is_the_scaled_similarity_solution(analysis):
    data = analysis("fig05")
    x, y = data.arrays["series/theory/x"], data.arrays["series/theory/y"]
    f0, peak = data.values["f0_airy"], data.values["peak_airy"]
    assert x[0] == 0.0 and y[0] == pytest.approx(0.0, abs=1e-15)
    assert y.max() == pytest.approx(f0 * peak, rel=1e-5)
    # the scaled data collapse on the curve: the largest scaled velocity of the last
    # snapshot is within 2% of the theory's peak
    last = data.arrays["series/t = 45.7/y"]
    assert last.max() == pytest.approx(f0 * peak, rel=0.02)


def test_fig06_and_fig07_scalings(analysis):
    data = analysis("fig06")
    x = data.arrays["series/n^5:6/x"]
    y56, y34 = data.arrays["series/n^5:6/y"], data.arrays["series/n^3:4/y"]
    np.testing.assert_allclose(y34, y56 * x ** (5 / 6 - 3 / 4), rtol=1e-12)
    data = analysis("fig07")
    for big_n in (100, 200, 400, 800):
        assert data.arrays[f"series/N={big_n}/x"][-1] == 0.0      # the last ball
        assert data.arrays[f"series/N={big_n}/y"][-1] == pytest.approx(
            data.values[f"coefficient_N{big_n}"], rel=1e-15)


def test_fig09_guide_is_the_printed_line(analysis):
    data = analysis("fig09")
    n = data.arrays["series/printed/x"]
    np.testing.assert_allclose(data.arrays["series/printed/y"], 0.084 * np.exp(-0.55 * n),
                               rtol=1e-15)


def test_fig12_and_fig13_master_curve_coordinates(analysis):
    data = analysis("fig12")
    for k in (3, 6, 9, 12):
        x = data.arrays[f"series/K={k}/x"]
        assert np.allclose((x * k - 0.5) % 1, 0.0, atol=1e-12)     # (N - n + 1/2)/K
        assert x[-1] == pytest.approx(0.5 / k)                      # n = N
    data = analysis("fig13")
    for k in (10, 20, 30, 40, 60, 80):
        x = data.arrays[f"series/K={k}/x"]
        np.testing.assert_allclose(x * k, np.arange(1, len(x) + 1), atol=1e-12)
        assert np.all(data.arrays[f"series/K={k}/y"] > 0)


# --------------------------------------------------------------- reproducible files
@pytest.mark.parametrize("name", ["fig05", "table1"])
def test_rendering_twice_gives_the_same_bytes(analysis, results, name):
    from chainrun.plotting import render

    analysis(name)
    first = {p: hashlib.sha256(p.read_bytes()).digest() for p in render(name, results=results)}
    second = {p: hashlib.sha256(p.read_bytes()).digest() for p in render(name, results=results)}
    assert first == second
    assert {p.suffix for p in first} == {Path(o).suffix for o in artefacts.get(name).outputs}


def test_table1_files(analysis, results):
    from chainrun.plotting import render

    analysis("table1")
    md, csv = render("table1", results=results)
    text = md.read_text()
    assert "| 5 | 0.9888 | 1.140 | 1.113 | 1.071 |" in text
    assert "0.8730 [1]" in text and "1.014 [2]" in text
    rows = csv.read_text().splitlines()
    assert rows[0] == "n,K,computed,paper" and len(rows) == 21


def test_comparison_files_from_an_analysis(tmp_path):
    from chainrun.plotting import comparison
    from chainrun.store import AnalysisData

    table = {
        "key": np.array(["a", "b"]), "where": np.array(["§1", "Fig 2"]),
        "quantity": np.array(["x", "y"]), "paper": np.array(["0.5", "1/4"]),
        "computed": np.array([0.5001, 0.3]), "agrees": np.array([True, False]),
        "rule": np.array(["printed", "exact"]), "note": np.array(["", "because, | why"]),
    }
    data = AnalysisData(name="paper-comparison", title="", descriptions={}, attrs={},
                        settings={}, inputs=[],
                        values={"rows": 2, "agreeing": 1, "explained": 1, "unexplained": 0},
                        arrays={f"table/{k}": v for k, v in table.items()})
    out = comparison.write(data)
    lines = out[".csv"].splitlines()
    assert lines[0] == "key,where,quantity,paper,computed,spread,agrees,rule,note"
    assert lines[2] == 'b,Fig 2,y,1/4,0.3,—,false,exact,"because, | why"'
    assert "**2 numbers: 1 agree, 1 disagree" in out[".md"]
    assert "### b" in out[".md"] and "because, \\| why" not in out[".md"].split("### b")[1]


def test_a_comparison_number_prints_no_digit_beyond_its_spread():
    """A value whose runs move by 3e-4 at a tenth of the tolerance: chainrun's 0.148611
    is shown as 0.149, and agrees with a printed 0.149 only within that spread."""
    from chainrun.analysis.paper import Printed, agrees, render_note
    from chainrun.plotting import comparison
    from chainrun.store import AnalysisData

    entry = Printed("c", "§5a", "second ejected ball", "0.1489", "sec5a/ejected_2")
    value, spread = 0.148611, 3e-4
    assert not agrees(entry, value) and agrees(entry, value, spread)
    assert not agrees(entry, value, 1e-5)
    note = render_note("ejected at {sec5a/ejected_2:.5f}", {"sec5a": {"ejected_2": value}},
                       {"sec5a": {"ejected_2": spread}})
    assert note == "ejected at 0.149"
    table = {
        "key": np.array(["c", "d"]), "where": np.array(["§5a", "§5a"]),
        "quantity": np.array(["x", "y"]), "paper": np.array(["0.1489", "0.25"]),
        "computed": np.array([value, 0.2500004]), "spread": np.array([spread, 1e-13]),
        "agrees": np.array([True, True]), "by_spread": np.array([True, False]),
        "rule": np.array(["printed", "printed"]), "note": np.array(["", ""]),
    }
    data = AnalysisData(name="paper-comparison", title="", descriptions={}, attrs={},
                        settings={}, inputs=[],
                        values={"rows": 2, "agreeing": 2, "explained": 0, "unexplained": 0,
                                "by_spread": 1},
                        arrays={f"table/{k}": v for k, v in table.items()})
    out = comparison.write(data)
    csv = out[".csv"].splitlines()
    assert csv[1] == "c,§5a,x,0.1489,0.149,3e-04,true,printed,"
    assert csv[2] == "d,§5a,y,0.25,0.25,1e-13,true,printed,"   # .6g: the spread cuts none
    assert "| c | §5a | x | 0.1489 | 0.149 | 3e-04 | yes, within the spread |" in out[".md"]
    assert "2 agree (1 only within chainrun's spread)" in out[".md"]
    for row, computed in ((csv[1], value), (csv[2], 0.2500004)):
        shown, spread_ = row.split(",")[4:6]
        decimals = len(shown.split(".")[1])
        # no digit shown below the spread: one unit of the last digit is at least it
        assert 10.0 ** -decimals >= float(spread_)
        assert abs(float(shown) - computed) <= 0.5 * 10.0 ** -decimals


def test_the_gallery_table_prints_no_digit_beyond_a_spread():
    from chainrun.plotting import gallery_comparison
    from chainrun.store import AnalysisData

    table = {"key": ["e", "f"], "item": ["wall", "wall"], "where": ["a paper", "closed form"],
             "quantity": ["x", "error"], "published": ["0.1489", "0"],
             "computed": [0.148611, 7.1234e-13], "spread": [3e-4, 6e-13],
             "status": ["agrees within the spread", "agrees"], "note": ["", ""]}
    data = AnalysisData(name="gallery-comparison", title="", descriptions={}, attrs={},
                        settings={}, inputs=[],
                        values={"rows": 2, "agrees": 2, "explained": 0, "cannot_be_checked": 0,
                                "unexplained": 0, "by_spread": 1},
                        arrays={f"table/{k}": np.array(v) for k, v in table.items()})
    out = gallery_comparison.write(data)
    csv = out[".csv"].splitlines()
    assert csv[0] == "key,item,where,quantity,published,computed,spread,status,note"
    assert csv[1] == "e,wall,a paper,x,0.1489,0.149,3e-04,agrees within the spread,"
    # an error of 7e-13 whose own spread is 6e-13 holds not one digit
    assert csv[2] == "f,wall,closed form,error,0,~7e-13,6e-13,agrees,"
    assert "2 agree (1 only within chainrun's spread)" in out[".md"]
