"""The two-body physics of a damped collision (``chainrun.solver.restitution``).

Reference values come from the explicit solution of the damped oscillator (its force's
zero found by a root finder in ``closed_forms.oscillator``, not by the module's
formulas), from the elastic closed forms of ``closed_forms.py``, and from first-order
perturbation theory.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import beta as beta_fn

from chainrun.solver import restitution as r
from closed_forms import contact_duration as elastic_duration
from closed_forms import oscillator


@pytest.mark.parametrize("eta", [1e-3, 0.1, 0.7, 1.5, 2.0 * math.sqrt(0.6 * 2.5) * 0.999,
                                 2.0 * math.sqrt(0.6 * 2.5) * 1.001, 4.0, 30.0])
def test_linear_dashpot_closed_form(eta):
    # k = 2.5, mu = 0.6: under-, near-critically and over-damped
    k, mu = 2.5, 0.6
    for v in (1e-3, 0.8, 1e3):
        e, t = oscillator(eta, k, mu, v)
        assert r.restitution(eta, 0.0, k, 1.0, mu, v) == pytest.approx(e, rel=1e-12)
        assert r.contact_duration(eta, 0.0, k, 1.0, mu, v) == pytest.approx(t, rel=1e-11)


def test_linear_dashpot_critical_and_limits():
    # critical damping (G = 2): e = exp(-2), t = 2 sqrt(mu/k) exactly
    e, tau = r.scaled_collision(2.0, 1.0, 0.0)
    assert e == pytest.approx(math.exp(-2.0), rel=1e-15)
    assert tau == 2.0
    assert r.scaled_collision(0.0, 1.0, 0.0) == pytest.approx((1.0, math.pi), rel=1e-15)
    # strongly over-damped: e ~ 1/G^2
    e, _ = r.scaled_collision(1e4, 1.0, 0.0)
    assert e * 1e8 == pytest.approx(1.0, rel=1e-3)


@pytest.mark.parametrize("g", [1e-3, 0.1, 0.9, 2.0, 3.0, 30.0])
def test_integration_meets_the_closed_form(g):
    e, tau = r._integrate(g, 1.0, 0.0, r.RTOL)
    ec, tc = r._linear(g)
    assert e == pytest.approx(ec, rel=1e-12)
    assert tau == pytest.approx(tc, rel=1e-10)


@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.0, 3.0])
def test_undamped_duration(alpha):
    # G = 0: e = 1 and the elastic duration (Beta function, closed_forms.py)
    k, mu, v = 1.7, 0.4, 2.3
    assert r.restitution(0.0, 0.25, k, alpha, mu, v) == 1.0
    assert r.contact_duration(0.0, 0.25, k, alpha, mu, v) == pytest.approx(
        elastic_duration(mu, k, alpha, v), rel=1e-13)


@pytest.mark.parametrize("alpha, beta", [(1.5, 0.5), (1.5, 0.25), (2.0, 0.5), (3.0, 1.0)])
def test_weak_damping_meets_perturbation_theory(alpha, beta):
    # 1 - e = (energy lost)/(2 E) to first order in G: G int s^beta s'^2 dtau along the
    # elastic collision = 2 G s_m^(beta+1) B((beta+1)/p, 3/2)/p, p = alpha + 1. The
    # early end (force zero before s = 0) costs O(G^((alpha+1)/(alpha-beta))), of
    # order G^2 or smaller here; Richardson on G and 2G removes the O(G^2) term. The
    # difference amplifies e's error (1e-12) by 2.5e5: hence 1e-6.
    p = alpha + 1.0
    slope = 2.0 * (p / 2.0) ** ((beta + 1.0) / p) * beta_fn((beta + 1.0) / p, 1.5) / p
    g = 1e-5
    d1 = 1.0 - r.scaled_collision(g, alpha, beta)[0]
    d2 = 1.0 - r.scaled_collision(2 * g, alpha, beta)[0]
    assert (4 * d1 - d2) / (2 * g) == pytest.approx(slope, rel=1e-6)
    if (alpha, beta) == (1.5, 0.5):
        # the Kuwabara-Kono constant of Schwager and Poeschel (1998), C1 = 1.15344
        assert slope == pytest.approx(1.15344, abs=1e-5)


@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.0])
@pytest.mark.parametrize("e", [0.99, 0.9, 0.5, 0.1])
def test_tsuji_restitution_is_independent_of_speed(alpha, e):
    k, mu = 3.0, 0.7
    eta = r.damping_for_restitution(e, "tsuji", k, alpha, mu)
    assert eta == pytest.approx(r.damping_for_restitution(e, "tsuji", k, alpha, mu, 5.0),
                                rel=1e-15)
    beta = (alpha - 1.0) / 2.0
    for v in (1e-3, 1e-2, 0.1, 1.0, 10.0, 100.0, 1e3):
        assert r.restitution(eta, beta, k, alpha, mu, v) == pytest.approx(e, abs=1e-9)


@pytest.mark.parametrize("law, alpha", [("dashpot", 1.0), ("dashpot", 1.5),
                                        ("kuwabara-kono", 1.5), ("kuwabara-kono", 1.0),
                                        ("tsuji", 1.5), ("tsuji", 2.0)])
@pytest.mark.parametrize("e", [1 - 1e-6, 0.95, 0.6, 0.2, 1e-3])
def test_damping_for_restitution_round_trip(law, alpha, e):
    k, mu, v = 2.0e9, 0.03, 0.4           # SI-like: a steel bead's scales
    eta = r.damping_for_restitution(e, law, k, alpha, mu, v)
    beta = r.law_exponent(law, alpha)
    assert r.restitution(eta, beta, k, alpha, mu, v) == pytest.approx(e, abs=1e-10)


def test_speed_dependent_laws_change_with_speed():
    k, mu = 1.0, 1.0
    eta = r.damping_for_restitution(0.8, "kuwabara-kono", k, 1.5, mu, speed=1.0)
    slow, fast = (r.restitution(eta, 0.5, k, 1.5, mu, v) for v in (0.1, 10.0))
    assert slow > 0.8 > fast        # viscoelastic Hertz: e falls with the impact speed


def test_law_exponents():
    assert r.law_exponent("dashpot", 1.5) == 0.0
    assert r.law_exponent("kuwabara-kono", 1.5) == 0.5
    assert r.law_exponent("tsuji", 1.5) == 0.25
    assert r.law_exponent("tsuji", 1.0) == 0.0
    assert r.is_speed_free(1.0, 0.0) and r.is_speed_free(1.5, 0.25)
    assert not r.is_speed_free(1.5, 0.5) and not r.is_speed_free(1.5, 0.0)


def test_elastic_restitution_needs_no_damping():
    assert r.damping_for_restitution(1.0, "kuwabara-kono", 1.0, 1.5, 1.0, 1.0) == 0.0
    assert r.damping_for_restitution(1.0, "tsuji", 1.0, 1.5, 1.0) == 0.0


@pytest.mark.parametrize("call, match", [
    (lambda: r.law_exponent("hertz", 1.5), "unknown damping law 'hertz'.*'tsuji'"),
    (lambda: r.damping_for_restitution(0.0, "tsuji", 1, 1.5, 1), r"in \(0, 1\], got 0.0"),
    (lambda: r.damping_for_restitution(1.2, "tsuji", 1, 1.5, 1), r"in \(0, 1\], got 1.2"),
    (lambda: r.damping_for_restitution(math.nan, "tsuji", 1, 1.5, 1), "in \\(0, 1\\]"),
    (lambda: r.damping_for_restitution(0.9, "kuwabara-kono", 1, 1.5, 1),
     "depends on the impact speed"),
    (lambda: r.damping_for_restitution(0.9, "dashpot", 1, 1.5, 1),
     "depends on the impact speed"),
    (lambda: r.damping_for_restitution(0.9, "tsuji", 1, 1.5, 1, speed=-1.0),
     "speed must be a finite number > 0"),
    (lambda: r.damping_for_restitution(0.9, "tsuji", 0.0, 1.5, 1), "stiffness"),
    (lambda: r.restitution(-1.0, 0.0, 1, 1.0, 1, 1), "damping must be .* >= 0, got -1.0"),
    (lambda: r.restitution(1.0, -0.5, 1, 1.0, 1, 1), "damping_exponent must be"),
    (lambda: r.restitution(1.0, 0.0, 1, 1.0, 0.0, 1), "reduced_mass"),
])
def test_bad_input(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_no_scipy_at_import():
    # start-up time: scipy is imported only when a collision is computed
    import subprocess
    import sys

    code = ("import sys, chainrun.solver.restitution; "
            "print(any(m == 'scipy' or m.startswith('scipy.') for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


def test_damping_for_restitution_on_arrays():
    # a line of contacts: each its own masses, stiffness and exponent, one solve per (e, alpha)
    e = np.array([0.9, 0.9, 0.5, 1.0, 0.9])
    k = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
    alpha = np.array([1.5, 1.5, 1.5, 2.0, 1.0])
    mu = np.array([0.5, 0.25, 1.0, 2.0, 0.5])
    eta = r.damping_for_restitution(e, "tsuji", k, alpha, mu)
    assert eta.shape == (5,) and eta[3] == 0.0
    for i in range(5):
        assert eta[i] == r.damping_for_restitution(float(e[i]), "tsuji", float(k[i]),
                                                   float(alpha[i]), float(mu[i]))
    # Kuwabara-Kono is speed-free at alpha = 2 (beta = 1/2 = (alpha - 1)/2)
    eta = r.damping_for_restitution(0.7, "kuwabara-kono", 1.0, 2.0, 1.0)
    assert r.restitution(eta, 0.5, 1.0, 2.0, 1.0, 123.0) == pytest.approx(0.7, abs=1e-10)


@pytest.mark.parametrize("law", ["dashpot", "kuwabara-kono", "tsuji"])
@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.1367658714971833, 3.0])
@pytest.mark.parametrize("e", [1 - 1e-16, 1 - 1e-12, 1 - 1.0001e-9, 1 - 0.9999e-9])
def test_restitution_within_rounding_of_one(law, alpha, e):
    # The integration's e is accurate to ~1e-12, so it cannot find a damping for
    # 1 - e below that (the fuzzer's e = 0.9999999999999999 made it fail); the first
    # order in the damping does. Either way the damping gives e back to that accuracy,
    # and it is continuous where one method hands over to the other.
    k, mu, v = 1.0, 0.5, 1.0
    eta = r.damping_for_restitution(e, law, k, alpha, mu, v)
    assert eta > 0.0
    beta = r.law_exponent(law, alpha)
    assert r.restitution(eta, beta, k, alpha, mu, v) == pytest.approx(e, abs=3e-12)
    if e == 1 - 1.0001e-9:
        below = r.damping_for_restitution(1 - 0.9999e-9, law, k, alpha, mu, v)
        assert below / eta == pytest.approx(0.9999e-9 / 1.0001e-9, rel=2e-3)
