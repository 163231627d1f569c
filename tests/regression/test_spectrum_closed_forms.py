"""The linear spectrum against closed forms: chains of springs between walls, with a free
end, periodic lines (monatomic, dimer), a light impurity, and real beads in SI.

Each reference is written here (``tests/closed_forms.py``), with the linear stiffness
``K = alpha kappa delta0^(alpha - 1)`` computed from the load in the test; where no
closed form exists (walls stiffer than the contacts, masses in turn), a dense
generalized eigenproblem ``K x = omega^2 M x`` built here by scipy.linalg.eigh.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
from closed_forms import (
    STEEL,
    dimer_band_edges,
    light_impurity_mode,
    modes_between_walls,
    modes_free_and_wall,
    monatomic_dispersion,
    shapes_between_walls,
)

import chainrun
from chainrun.analysis.spectrum import band_edges, dispersion, line_spectrum
from chainrun.solver import Line, Wall
from chainrun.solver.model import precompress

RTOL = 1e-10


def hertz_K(kappa: float, alpha: float, load: float) -> float:
    """Linear stiffness of a contact ``kappa delta^alpha`` carrying ``load``."""
    delta0 = (load / kappa) ** (1.0 / alpha)
    return alpha * kappa * delta0 ** (alpha - 1.0)


@pytest.mark.parametrize("n", [1, 2, 7, 40])
def test_linear_line_between_two_walls(n):
    m, kappa = 1.7, 2.3
    # touching linear contacts take their stiffness kappa, whatever the load
    line = Line.make(n, k=0, mass=m, stiffness=kappa, alpha=1.0,
                     left=Wall(kappa, 1.0), right=Wall(kappa, 1.0))
    ds = line_spectrum(line)
    np.testing.assert_allclose(ds.omega, modes_between_walls(kappa, m, n), rtol=RTOL)
    np.testing.assert_allclose(ds.frequency, ds.omega / (2 * math.pi), rtol=1e-15)
    # mode shapes: sin(i j pi / (n + 1)), largest magnitude 1, the first ball forward
    ref = shapes_between_walls(n)
    ref /= np.max(np.abs(ref), axis=0) * np.sign(ref[0])
    np.testing.assert_allclose(ds.shape.values, ref.T, atol=1e-10)
    assert ds.attrs["zero_modes"] == 0 and ds.attrs["loaded_contacts"] == 0


@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.5])
def test_precompressed_line_between_two_walls(alpha):
    n, m, kappa, load = 25, 0.8, 1.9, 0.37
    line = precompress(Line.make(n, k=0, mass=m, stiffness=kappa, alpha=alpha,
                                 left=Wall(kappa, alpha), right=Wall(kappa, alpha)), load)
    ds = line_spectrum(line)
    K = hertz_K(kappa, alpha, load)
    np.testing.assert_allclose(ds.omega, modes_between_walls(K, m, n), rtol=RTOL)
    np.testing.assert_allclose(ds.linear_stiffness, K, rtol=1e-13)
    np.testing.assert_allclose(ds.static_force, load, rtol=1e-13)
    np.testing.assert_allclose(ds.static_compression, (load / kappa) ** (1 / alpha), rtol=1e-13)
    assert list(ds.contact.values) == list(range(n + 1))  # both walls' contacts too


@pytest.mark.parametrize("k", [0, 1, 3])
def test_free_end_and_a_wall(k):
    # precompressed against one wall by a force on the first resting ball: that end is
    # free for small motions (the force is constant); the strikers are left out
    n, m, kappa, alpha, load = 30, 1.3, 0.7, 1.5, 2.0
    line = precompress(Line.make(n + k, k=k, mass=m, stiffness=kappa, alpha=alpha,
                                 right=Wall(kappa, alpha)), load)
    ds = line_spectrum(line)
    K = hertz_K(kappa, alpha, load)
    np.testing.assert_allclose(ds.omega, modes_free_and_wall(K, m, n), rtol=RTOL)
    assert ds.attrs["strikers_left_out"] == k
    assert list(ds.ball.values) == list(range(k + 1, n + k + 1))


def test_periodic_monatomic_line():
    n, m, kappa, alpha, load = 12, 2.0, 3.0, 1.5, 0.5
    line = precompress(Line.make(n, k=0, mass=m, stiffness=kappa, alpha=alpha,
                                 left=Wall(5.0, alpha), right=Wall(5.0, alpha)), load)
    ds = line_spectrum(line)
    K = hertz_K(kappa, alpha, load)
    assert ds.attrs["period"] == 1
    np.testing.assert_allclose(ds.dispersion.sel(branch=1),
                               monatomic_dispersion(K, m, ds.q.values), rtol=RTOL, atol=0)
    assert ds.band_bottom.item() == 0.0
    np.testing.assert_allclose(ds.band_top.item(), 2 * math.sqrt(K / m), rtol=RTOL)
    # the finite line's modes lie in the band
    assert float(ds.omega.max()) < float(ds.band_top.item())


@pytest.mark.parametrize("first", ["heavy", "light"])
def test_dimer_band_edges(first):
    m1, m2, kappa, alpha, load = 3.0, 1.1, 1.4, 1.5, 0.8
    masses = [m1, m2] if first == "heavy" else [m2, m1]
    line = precompress(Line.make(20, k=0, mass=np.tile(masses, 10), stiffness=kappa,
                                 alpha=alpha, left=Wall(kappa, alpha),
                                 right=Wall(kappa, alpha)), load)
    ds = line_spectrum(line)
    K = hertz_K(kappa, alpha, load)
    acoustic_top, optical_bottom, optical_top = dimer_band_edges(K, m1, m2)
    assert ds.attrs["period"] == 2
    np.testing.assert_allclose(ds.band_bottom, [0.0, optical_bottom], rtol=RTOL)
    np.testing.assert_allclose(ds.band_top, [acoustic_top, optical_top], rtol=RTOL)
    # each branch stays within its edges at every q (the edges are at q = 0 and pi)
    branches = ds.dispersion.values
    assert np.all(branches >= ds.band_bottom.values * (1 - 1e-14))
    assert np.all(branches <= ds.band_top.values * (1 + 1e-14))


def test_dispersion_is_the_spectrum_of_a_ring_of_cells():
    # A ring of L cells has exactly the modes of the infinite line at q = 2 pi l / L:
    # built here as a dense (L P) x (L P) problem, a cell of three unlike balls.
    mass, springs = np.array([1.0, 2.5, 0.7]), np.array([1.3, 0.4, 2.2])
    cells, p = 8, 3
    total = cells * p
    m = np.tile(mass, cells)
    k = np.tile(springs, cells)  # k[i] joins ball i and ball i + 1 (mod total)
    stiff = np.zeros((total, total))
    for i in range(total):
        j = (i + 1) % total
        stiff[i, i] += k[i]
        stiff[j, j] += k[i]
        stiff[i, j] -= k[i]
        stiff[j, i] -= k[i]
    ring = np.sqrt(np.clip(scipy.linalg.eigh(stiff, np.diag(m), eigvals_only=True), 0, None))
    q = 2 * math.pi * np.arange(cells) / cells
    line = np.sort(dispersion(mass, springs, q).ravel())
    np.testing.assert_allclose(line, ring, rtol=1e-10, atol=1e-7)
    bottom, top = band_edges(mass, springs)
    fine = dispersion(mass, springs, np.linspace(0, math.pi, 2001))
    np.testing.assert_allclose(fine.min(axis=0), bottom, rtol=1e-12)
    np.testing.assert_allclose(fine.max(axis=0), top, rtol=1e-12)


def test_light_impurity_has_a_localised_mode_above_the_band():
    n, m, kappa, alpha, load, light = 61, 1.0, 1.0, 1.5, 1.0, 0.3
    mass = np.full(n, m)
    mass[n // 2] = light
    line = precompress(Line.make(n, k=0, mass=mass, stiffness=kappa, alpha=alpha,
                                 left=Wall(kappa, alpha), right=Wall(kappa, alpha)), load)
    ds = line_spectrum(line)
    K = hertz_K(kappa, alpha, load)
    assert ds.attrs["period"] == 0 and "dispersion" not in ds
    # 30 balls from either wall, the infinite line's mode is exact to (0.3/1.7)^60
    np.testing.assert_allclose(ds.omega.values[-1], light_impurity_mode(K, m, light),
                               rtol=RTOL)
    top = ds.shape.isel(mode=-1).values
    assert abs(top[n // 2]) == 1.0
    np.testing.assert_allclose(abs(top[n // 2 + 1]), (1 - 0.7) / (1 + 0.7), rtol=1e-10)


def test_real_beads_between_walls_in_si():
    # 20 steel beads of 25.4 mm between two walls as stiff as a bead pair, under 10 N:
    # kappa, the mass and K from the Hertz constants here, the frequencies in rad/s
    E, nu, rho, d = STEEL["E"], STEEL["nu"], STEEL["rho"], STEEL["d"]
    n, load = 20, 10.0
    kappa = E * math.sqrt(d) / (3 * (1 - nu * nu))
    mass = rho * math.pi * d ** 3 / 6
    wall = {"stiffness": kappa, "alpha": 1.5}
    ds = chainrun.spectrum(units="si", chain={
        "n": n, "k": 0, "diameter": d, "young": E, "poisson": nu, "density": rho,
        "precompression": load}, walls={"left": wall, "right": wall})
    K = hertz_K(kappa, 1.5, load)
    np.testing.assert_allclose(ds.omega, modes_between_walls(K, mass, n), rtol=RTOL)
    assert ds.omega.attrs["units"] == "rad/s" and ds.frequency.attrs["units"] == "Hz"
    assert ds.linear_stiffness.attrs["units"] == "N/m" and ds.attrs["units"] == "SI"
    # K = 1.66e7 N/m, m = 67.4 g: the band's top 2 sqrt(K/m) / (2 pi) is 5.0 kHz
    assert K == pytest.approx(1.663e7, rel=1e-3) and mass == pytest.approx(0.06737, rel=1e-3)
    assert 4.9e3 < float(ds.frequency.max()) < 5.0e3


def test_real_dimer_with_steel_walls_against_a_dense_solve():
    # stainless steel and aluminium in turn between flat steel walls, whose contacts
    # are stiffer than the beads' (R* = R): no closed form, so K x = omega^2 M x dense,
    # from the presets' constants (data with their sources) and Hertz's law written here
    from chainrun.materials import MATERIALS

    names = ["stainless_steel", "aluminium"] * 5
    E = np.array([MATERIALS[n].young for n in names])
    nu = np.array([MATERIALS[n].poisson for n in names])
    rho = np.array([MATERIALS[n].density for n in names])
    d, load, n = 0.01905, 5.0, 10
    R = d / 2
    mass = rho * math.pi * d ** 3 / 6

    def kappa(e1, n1, r1, e2, n2, r2):
        e_star = 1 / ((1 - n1 ** 2) / e1 + (1 - n2 ** 2) / e2)
        r_star = r1 if r2 == math.inf else r1 * r2 / (r1 + r2)
        return 4 / 3 * e_star * math.sqrt(r_star)

    ws = MATERIALS["steel"]
    kap = [kappa(E[0], nu[0], R, ws.young, ws.poisson, math.inf)]
    kap += [kappa(E[i], nu[i], R, E[i + 1], nu[i + 1], R) for i in range(n - 1)]
    kap += [kappa(E[-1], nu[-1], R, ws.young, ws.poisson, math.inf)]
    springs = np.array([hertz_K(c, 1.5, load) for c in kap])
    stiff = np.diag(springs[:-1] + springs[1:]) - np.diag(springs[1:-1], 1) \
        - np.diag(springs[1:-1], -1)
    ref = np.sqrt(scipy.linalg.eigh(stiff, np.diag(mass), eigvals_only=True))

    ds = chainrun.spectrum(units="si", chain={
        "n": n, "k": 0, "diameter": d, "material": {"pattern": ["stainless_steel", "aluminium"]},
        "precompression": load}, walls={"left": {"material": "steel"},
                                        "right": {"material": "steel"}})
    np.testing.assert_allclose(ds.omega, ref, rtol=1e-12)
    np.testing.assert_allclose(ds.mass, mass, rtol=1e-14)
    np.testing.assert_allclose(ds.linear_stiffness, springs, rtol=1e-12)
    # shapes solve K x = omega^2 M x
    x = ds.shape.values.T
    residual = stiff @ x - mass[:, None] * x * ds.omega.values ** 2
    assert np.max(np.abs(residual)) < 1e-12 * np.max(springs)
