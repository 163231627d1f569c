"""The benchmark harness (``benchmarks/``): its peers agree with chainrun on a short
line, and its bookkeeping (exponent fits, agreement check, configs) is right.

The benchmarks themselves run with ``make bench``; this only keeps the instrument
honest, in a few seconds.
"""

from __future__ import annotations

import re
import shutil
import subprocess

import numpy as np
import pytest

from benchmarks import run
from benchmarks.peers import rk4_paper, scipy_dop853
from chainrun.config import parse_experiment
from chainrun.solver import simulate


@pytest.fixture(scope="module")
def hertz_line():
    n = 12
    t_stop = 1.25 * n + 20
    return n, t_stop, simulate(n, 1, 1.5, t_end=t_stop, rtol=1e-14).final_velocity


def test_scipy_peer_agrees_with_chainrun(hertz_line):
    n, t_stop, v_ref = hertz_line
    r = scipy_dop853.solve(n, 1, 1.5, t_stop)
    assert r.t_end == t_stop
    assert np.max(np.abs(r.final_velocity - v_ref)) < run.ACCURACY["scipy"]
    assert abs(r.final_velocity.sum() - 1.0) < 1e-12          # momentum
    assert r.events >= n - 1 - 2 and r.steps > 0


def test_rk4_peer_agrees_with_chainrun_to_its_accuracy(hertz_line):
    n, t_stop, v_ref = hertz_line
    r = rk4_paper.solve(n, 1, 1.5, t_stop)
    err = np.max(np.abs(r.final_velocity - v_ref))
    assert err < run.ACCURACY["rk4"]
    assert abs(r.final_velocity.sum() - 1.0) < 1e-12


def test_heyoka_peer_agrees_with_chainrun(hertz_line):
    pytest.importorskip("heyoka")
    from benchmarks.peers import heyoka_peer

    n, t_stop, v_ref = hertz_line
    r = heyoka_peer.solve(n, 1, 1.5, t_stop)
    assert np.max(np.abs(r.final_velocity - v_ref)) < run.ACCURACY["heyoka"]
    assert r.compile_time > 0


def test_linear_peers_agree_with_chainrun():
    n = 10
    ref = simulate(n, 1, 1.0, rtol=1e-14)
    for solve, claim in ((scipy_dop853.solve, "scipy"), (rk4_paper.solve, "rk4")):
        r = solve(n, 1, 1.0, ref.end_time)
        assert np.max(np.abs(r.final_velocity - ref.final_velocity)) < run.ACCURACY[claim]


def test_fit_exponent_recovers_a_power_law():
    ns = [100, 1000, 10_000, 100_000]
    fit = run.fit_exponent(ns, [1e-3 * n**1.5 for n in ns])
    assert fit["exponent"] == pytest.approx(1.5)
    assert fit["local_exponent"] == pytest.approx(1.5)
    # start-up dominated points (under 0.05 s) are left out while two others remain
    fit = run.fit_exponent(ns, [0.01, 0.01, 0.1, 1.0])
    assert fit["exponent"] == pytest.approx(1.0) and fit["n_min"] == 10_000
    assert run.fit_exponent([100], [1.0]) is None


def test_agreement_flags_a_disagreement():
    v = np.linspace(0.0, 1.0, 5)
    tools = [{"tool": "chainrun", "final_velocity": v, "error_vs_reference": 0.0},
             {"tool": "scipy", "final_velocity": v + 1e-12, "error_vs_reference": 1e-12},
             {"tool": "rk4", "final_velocity": v + 1e-7, "error_vs_reference": 1e-7}]
    assert run.agreement(tools)["ok"]
    tools.append({"tool": "heyoka", "final_velocity": v + 1e-6, "error_vs_reference": 1e-6})
    ag = run.agreement(tools)
    assert not ag["ok"]
    assert {(p["a"], p["b"]) for p in ag["pairs"] if not p["ok"]} == {
        ("chainrun", "heyoka"), ("scipy", "heyoka")}
    assert [o["tool"] for o in ag["off"]] == ["heyoka"]


def test_generated_config_is_a_valid_experiment():
    text = run.config_text("bench-x", 1000, 1, 1.5, t_end=1270.0,
                           times=np.linspace(0.0, 1270.0, 200))
    exp = parse_experiment(text, "toml")
    (spec,) = exp.runs()
    assert (spec.n, spec.k, spec.alpha, spec.t_end) == (1000, 1, 1.5, 1270.0)
    assert spec.times.size == 200 and spec.times[-1] == 1270.0


def _git(*args, cwd):
    return subprocess.run(["git", *args], cwd=cwd, check=True, capture_output=True,
                          text=True).stdout.strip()


def test_git_commit_is_read_without_git(tmp_path):
    """The commit read from .git's files is git's own, on a branch, a detached head and
    with the branch's ref packed; a folder that is no repository gives None."""
    if shutil.which("git") is None:
        pytest.skip("git is not installed")
    repo = tmp_path / "repo"
    repo.mkdir()
    env = ["-c", "user.name=t", "-c", "user.email=t@t"]
    _git("init", "-q", cwd=repo)
    (repo / "a").write_text("a")
    _git("add", "a", cwd=repo)
    _git(*env, "commit", "-q", "-m", "a", cwd=repo)
    head = _git("rev-parse", "HEAD", cwd=repo)
    assert re.fullmatch(r"[0-9a-f]{40}", head)
    assert run.git_commit(repo) == head  # loose ref
    _git("pack-refs", "--all", cwd=repo)
    assert run.git_commit(repo) == head  # packed ref
    _git("checkout", "-q", "--detach", cwd=repo)
    assert run.git_commit(repo) == head  # detached
    assert run.git_commit(tmp_path / "none") is None
