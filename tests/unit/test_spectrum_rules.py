"""The linear spectrum's rules (chainrun.analysis.spectrum): which contacts are stiff, zero
modes, the strikers left out, the static-state check, periods, limits; and the spectrum
file (chainrun.store), read back by chainrun and by xarray's h5netcdf engine."""

from __future__ import annotations

import math
import re
from pathlib import Path

import h5py
import numpy as np
import pytest
import xarray as xr

from chainrun import atomic, store
from chainrun.analysis import spectrum as sp
from chainrun.errors import ChainrunError, StoreError
from chainrun.solver import Line, Wall
from chainrun.solver.model import precompress

#: what the store adds to a Dataset as it writes it
STAMP = ("format", "format_version", "created", "creator_name", "creator_version")


def test_touching_contacts_linear_or_not_and_open_gaps():
    # contact 1: linear, touching -> kappa; 2: Hertz, touching -> 0; 3: a gap -> 0;
    # 4: linear, open by a gap -> 0
    line = Line.make(5, k=0, stiffness=[2.0, 3.0, 4.0, 5.0], alpha=[1.0, 1.5, 1.0, 1.0],
                     gap=[0.0, 0.0, 0.1, 0.2], right=Wall(1.5, 1.0))
    state = sp.static_state(line)
    np.testing.assert_array_equal(state.contacts, [1, 2, 3, 4, 5])
    np.testing.assert_array_equal(state.stiffness, [2.0, 0.0, 0.0, 0.0, 1.5])
    np.testing.assert_array_equal(state.compression, [0.0, 0.0, -0.1, -0.2, 0.0])
    np.testing.assert_array_equal(state.force, 0.0)
    np.testing.assert_array_equal(state.springs, [0.0, 2.0, 0.0, 0.0, 0.0, 1.5])


def test_free_pieces_have_exact_zero_modes():
    # balls 1-2 joined (linear, touching) and free; 3 alone; 4-5 held by the right wall
    line = Line.make(5, k=0, mass=[1.0, 3.0, 2.0, 1.0, 1.0], stiffness=[2.0, 1.0, 1.0, 1.0],
                     alpha=[1.0, 1.5, 1.5, 1.0], right=Wall(1.0, 1.0))
    ds = sp.line_spectrum(line)
    assert ds.attrs["zero_modes"] == 2 and ds.attrs["loaded_contacts"] == 0
    np.testing.assert_array_equal(ds.omega.values[:2], 0.0)
    # the free pair's relative motion: omega^2 = K (1/m1 + 1/m2); the held pair, a free
    # end and a wall: 2 sqrt(K/m) sin((2j - 1) pi / 10)
    expected = sorted([math.sqrt(2.0 * (1 + 1 / 3)), 2 * math.sin(math.pi / 10),
                       2 * math.sin(3 * math.pi / 10)])
    np.testing.assert_allclose(ds.omega.values[2:], expected, rtol=1e-13)
    # each zero mode moves one free piece rigidly, and nothing else
    zero = ds.shape.values[:2]
    moved = sorted(tuple(np.flatnonzero(z)) for z in zero)
    assert moved == [(0, 1), (2,)]
    for z in zero:
        np.testing.assert_array_equal(z[z != 0], 1.0)


def test_an_unloaded_hertz_line_has_only_zero_frequencies():
    line = Line.make(6, k=1, alpha=1.5, right=Wall(1.0))
    ds = sp.line_spectrum(line)
    assert ds.attrs["zero_modes"] == 5 and ds.attrs["strikers_left_out"] == 1
    np.testing.assert_array_equal(ds.omega, 0.0)
    np.testing.assert_array_equal(ds.shape, np.eye(5))
    # uniform, but its cells fall apart: no dispersion relation
    assert ds.attrs["period"] == 0 and "dispersion" not in ds
    with pytest.raises(ChainrunError, match="^period: a contact of the 1-ball cell has no "
                                            "linear stiffness"):
        sp.line_spectrum(line, period=1)


def test_a_line_not_at_rest_is_refused_naming_the_ball():
    # a force with nothing to hold it
    line = Line.make(4, k=0, alpha=1.5, force=[0.0, 0.0, 1.0, 0.0])
    with pytest.raises(ChainrunError) as info:
        sp.line_spectrum(line)
    assert str(info.value) == (
        "ball 3 is not at rest in a static state: the forces on it add up to 1 (largest "
        "force on the line 1); the spectrum is of a line at rest (chain.precompression "
        "places one)")
    # an overlap the walls do not hold, in SI
    line = Line.make(3, k=0, stiffness=1e9, alpha=1.5, gap=[-1e-6, 0.0])
    with pytest.raises(ChainrunError, match=r"^ball 1 is not at rest .* add up to -1 N "):
        sp.line_spectrum(line, "si")
    with pytest.raises(ChainrunError, match=r"^chain.k: every ball is a striker \(or moves"):
        sp.line_spectrum(Line.make(3, k=3, alpha=1.5))


def test_the_strikers_and_their_contacts_are_left_out():
    line = precompress(Line.make(6, k=2, alpha=1.5, right=Wall(1.0)), 1.0)
    state = sp.static_state(line)
    np.testing.assert_array_equal(state.balls, [3, 4, 5, 6])
    np.testing.assert_array_equal(state.contacts, [3, 4, 5, 6])  # 6: the right wall
    assert state.springs[0] == 0.0 and state.left_out == 2
    # a left wall touching a striker goes with it
    line = Line.make(4, k=1, alpha=1.0, left=Wall(1.0, 1.0), right=Wall(1.0, 1.0))
    state = sp.static_state(line)
    np.testing.assert_array_equal(state.contacts, [2, 3, 4])


def test_periods_found_given_and_refused():
    mass = np.tile([1.0, 2.0, 2.0], 4)
    line = precompress(Line.make(12, k=0, mass=mass, alpha=1.5, left=Wall(1.0),
                                 right=Wall(1.0)), 1.0)
    assert sp.line_spectrum(line).attrs["period"] == 3
    assert sp.line_spectrum(line, period=6).branch.size == 6  # a multiple is a period
    none = sp.line_spectrum(line, period=0)
    assert none.attrs["period"] == 0 and "dispersion" not in none and "q" not in none.dims
    with pytest.raises(ChainrunError) as info:
        sp.line_spectrum(line, period=2)
    assert str(info.value) == ("period: the line does not repeat every 2 balls: the mass "
                               "of ball 3 differs from ball 1's (counting the balls at "
                               "rest from 1)")
    with pytest.raises(ChainrunError, match="^period: a cell of 7 balls needs a line of at "
                                            "least 14 at rest, this one has 12$"):
        sp.line_spectrum(line, period=7)
    # stiffnesses count too: a taper is not periodic
    taper = precompress(Line.make(12, k=0, stiffness=0.9 ** np.arange(11), alpha=1.5,
                                  right=Wall(1.0)), 1.0)
    assert sp.line_spectrum(taper).attrs["period"] == 0
    with pytest.raises(ChainrunError, match="linear stiffness of the contact after ball 2 "):
        sp.line_spectrum(taper, period=1)


def test_a_folded_band_is_the_same_band():
    line = precompress(Line.make(12, k=0, alpha=1.5, left=Wall(1.0), right=Wall(1.0)), 1.0)
    one, two = sp.line_spectrum(line), sp.line_spectrum(line, period=2)
    # two balls per cell: the band [0, c] folds at c / sqrt(2), no gap in between
    c = float(one.band_top.item())
    np.testing.assert_allclose(two.band_bottom, [0.0, c / math.sqrt(2)], rtol=1e-14)
    np.testing.assert_allclose(two.band_top, [c / math.sqrt(2), c], rtol=1e-14)


def test_limits_on_the_length(monkeypatch):
    line = precompress(Line.make(12, k=0, alpha=1.5, right=Wall(1.0)), 1.0)
    monkeypatch.setattr(sp, "MAX_SHAPE_BALLS", 10)
    ds = sp.line_spectrum(line)
    assert "shape" not in ds and ds.omega.size == 12
    assert ds.attrs["shape_normalisation"].startswith("none")
    monkeypatch.setattr(sp, "MAX_BALLS", 11)
    with pytest.raises(ChainrunError, match=r"^chain.n: a line of 12 balls at rest is too "
                                            r"long for its spectrum \(at most 11\)$"):
        sp.line_spectrum(line)


def _dimer():
    line = precompress(Line.make(10, k=1, alpha=1.5, mass=np.tile([2.0, 1.0], 5),
                                 right=Wall(1.0)), 0.5)
    ds = sp.line_spectrum(line)
    ds.attrs.update(experiment="dimer", run_id="run", config_hash="0" * 64,
                    config="[chain]\nn = 10\n")
    return ds


def test_the_spectrum_file_reads_back_the_same(tmp_path):
    ds = _dimer()
    path = tmp_path / "run.h5"
    store.write_spectrum(path, ds)
    back = store.read_spectrum(path)
    assert back.attrs["format"] == "chainrun-spectrum" and back.attrs["format_version"] == 1
    for key in STAMP:
        back.attrs.pop(key)
    xr.testing.assert_identical(back, ds)
    # a plain netCDF-4 file: xarray's own reader sees the same Dataset
    with xr.open_dataset(path, engine="h5netcdf") as other:
        other = other.load()
    for key in STAMP:
        other.attrs.pop(key)
    xr.testing.assert_identical(other, ds)
    assert not atomic.leftovers(tmp_path, ["run.h5"])


def test_a_failed_write_leaves_the_old_file(tmp_path):
    path = tmp_path / "run.h5"
    store.write_spectrum(path, _dimer())
    before = path.read_bytes()
    bad = _dimer()
    bad.attrs["bad"] = [1, 2]
    with pytest.raises(StoreError, match="attribute @bad is not a str, int, float or bool"):
        store.write_spectrum(path, bad)
    assert path.read_bytes() == before
    assert not atomic.leftovers(tmp_path, ["run.h5"])


def test_reading_another_file_is_one_line(tmp_path):
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f.attrs["format"] = "chainrun-run"
        f.attrs["format_version"] = np.int64(1)
    with pytest.raises(StoreError, match=r"other.h5: not a chainrun spectrum file "
                                         r"\(format 'chainrun-run'\)$"):
        store.read_spectrum(other)
    with pytest.raises(StoreError, match="no such file"):
        store.read_spectrum(tmp_path / "missing.h5")


def test_every_item_is_in_the_schema_page(tmp_path):
    doc = (Path(__file__).resolve().parents[2] / "docs" / "schema.md").read_text()
    section = doc.split("## Spectrum file, format `chainrun-spectrum` version 1", 1)[1]
    path = tmp_path / "run.h5"
    store.write_spectrum(path, _dimer())
    names = set()
    with h5py.File(path, "r") as f:
        names |= set(f.attrs)
        for name, item in f.items():
            names.add(name)
            names.update(a for a in item.attrs
                         if a not in ("CLASS", "NAME", "REFERENCE_LIST", "DIMENSION_LIST"))
    missing = sorted(n for n in names if not re.search(rf"\b{re.escape(n)}\b", section))
    assert not missing, f"not in docs/schema.md: {missing}"
