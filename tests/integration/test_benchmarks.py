"""The benchmark harness (``benchmarks/``): its peers agree with chainrun on a short
line, and its bookkeeping (exponent fits, agreement check, configs) is right.

The benchmarks themselves run with ``make bench``; this only keeps the instrument
honest, in a few seconds.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

from benchmarks import harness, run, worktree
from benchmarks.peers import rk4_paper, scipy_dop853
from benchmarks.sections import general, peers, previous, targets
from chainrun.config import parse_experiment


@pytest.fixture(scope="module")
def hertz_line():
    n = 12
    t_stop = 1.25 * n + 20
    return n, t_stop, harness.solve_paper(n, 1, 1.5, t_end=t_stop, rtol=1e-14).final_velocity


def test_scipy_peer_agrees_with_chainrun(hertz_line):
    n, t_stop, v_ref = hertz_line
    r = scipy_dop853.solve(n, 1, 1.5, t_stop)
    assert r.t_end == t_stop
    assert np.max(np.abs(r.final_velocity - v_ref)) < harness.ACCURACY["scipy"]
    assert abs(r.final_velocity.sum() - 1.0) < 1e-12          # momentum
    assert r.events >= n - 1 - 2 and r.steps > 0


def test_rk4_peer_agrees_with_chainrun_to_its_accuracy(hertz_line):
    n, t_stop, v_ref = hertz_line
    r = rk4_paper.solve(n, 1, 1.5, t_stop)
    err = np.max(np.abs(r.final_velocity - v_ref))
    assert err < harness.ACCURACY["rk4"]
    assert abs(r.final_velocity.sum() - 1.0) < 1e-12


def test_heyoka_peer_agrees_with_chainrun(hertz_line):
    # heyoka is in the bench extra (its wheels are some 100 MB, Linux x86-64 only), not
    # in the test extra: `make bench` installs it and runs this file before it measures
    pytest.importorskip("heyoka", reason="heyoka is in the bench extra; `make bench` "
                        "installs it and runs this test")
    from benchmarks.peers import heyoka_peer

    n, t_stop, v_ref = hertz_line
    r = heyoka_peer.solve(n, 1, 1.5, t_stop)
    assert np.max(np.abs(r.final_velocity - v_ref)) < harness.ACCURACY["heyoka"]
    assert r.compile_time > 0


def test_a_missing_heyoka_leaves_its_peer_out_with_the_reason(monkeypatch):
    # Where heyoka is not installed (a plain `make test`), the harness runs the other
    # peers and says why heyoka is absent; importing it fails as if it were missing.
    from benchmarks.peers import PeerUnavailable, heyoka_peer

    monkeypatch.setitem(sys.modules, "heyoka", None)
    ok, why = heyoka_peer.available()
    assert not ok and "chainrun[bench]" in why
    assert heyoka_peer.version() is None
    with pytest.raises(PeerUnavailable, match="heyoka is not installed"):
        heyoka_peer.solve(3, 1, 1.5, 5.0)
    notes: list[str] = []
    runners = peers.peer_runners(run.Mode(full=False), notes)
    assert set(runners) == {"scipy", "rk4"}
    assert notes == [f"heyoka skipped: {why}"]
    result = peers.run_peer("heyoka", heyoka_peer.solve, 3, 1, 1.5, 5.0)
    assert result == {"tool": "heyoka", "n": 3, "error": why}


def test_linear_peers_agree_with_chainrun():
    n = 10
    ref = harness.solve_paper(n, 1, 1.0, rtol=1e-14)
    for solve, claim in ((scipy_dop853.solve, "scipy"), (rk4_paper.solve, "rk4")):
        r = solve(n, 1, 1.0, ref.end_time)
        assert np.max(np.abs(r.final_velocity - ref.final_velocity)) < harness.ACCURACY[claim]


def test_fit_exponent_recovers_a_power_law():
    ns = [100, 1000, 10_000, 100_000]
    fit = harness.fit_exponent(ns, [1e-3 * n**1.5 for n in ns])
    assert fit["exponent"] == pytest.approx(1.5)
    assert fit["local_exponent"] == pytest.approx(1.5)
    # start-up dominated points (under 0.05 s) are left out while two others remain
    fit = harness.fit_exponent(ns, [0.01, 0.01, 0.1, 1.0])
    assert fit["exponent"] == pytest.approx(1.0) and fit["n_min"] == 10_000
    assert harness.fit_exponent([100], [1.0]) is None


def test_agreement_flags_a_disagreement():
    v = np.linspace(0.0, 1.0, 5)
    tools = [{"tool": "chainrun", "final_velocity": v, "error_vs_reference": 0.0},
             {"tool": "scipy", "final_velocity": v + 1e-12, "error_vs_reference": 1e-12},
             {"tool": "rk4", "final_velocity": v + 1e-7, "error_vs_reference": 1e-7}]
    assert peers.agreement(tools)["ok"]
    tools.append({"tool": "heyoka", "final_velocity": v + 1e-6, "error_vs_reference": 1e-6})
    ag = peers.agreement(tools)
    assert not ag["ok"]
    assert {(p["a"], p["b"]) for p in ag["pairs"] if not p["ok"]} == {
        ("chainrun", "heyoka"), ("scipy", "heyoka")}
    assert [o["tool"] for o in ag["off"]] == ["heyoka"]


def test_generated_config_is_a_valid_experiment():
    text = harness.config_text("bench-x", 1000, 1, 1.5, t_end=1270.0,
                           times=np.linspace(0.0, 1270.0, 200))
    exp = parse_experiment(text, "toml")
    (spec,) = exp.runs()
    assert (spec.n, spec.k, spec.alpha, spec.t_end) == (1000, 1, 1.5, 1270.0)
    assert spec.times.size == 200 and spec.times[-1] == 1270.0


def test_processes_import_this_checkout(tmp_path, monkeypatch):
    """A ``chainrun simulate`` process runs in a scratch folder: a relative
    ``PYTHONPATH=.`` would name that folder there, so this checkout comes first."""
    seen = {}

    class Stop(Exception):
        pass

    def popen(cmd, **kwargs):
        seen.update(kwargs)
        raise Stop

    monkeypatch.setenv("PYTHONPATH", ".")
    monkeypatch.setattr(harness.subprocess, "Popen", popen)
    procs = harness.Processes(tmp_path)
    with pytest.raises(Stop):
        procs.run("name = 'x'\n")
    assert seen["env"]["PYTHONPATH"].split(os.pathsep) == [str(harness.ROOT), "."]
    with pytest.raises(Stop):                       # an environment given is kept
        procs.run("name = 'x'\n", env={"PYTHONPATH": "/old"})
    assert seen["env"] == {"PYTHONPATH": "/old"}


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
    assert harness.git_commit(repo) == head  # loose ref
    _git("pack-refs", "--all", cwd=repo)
    assert harness.git_commit(repo) == head  # packed ref
    _git("checkout", "-q", "--detach", cwd=repo)
    assert harness.git_commit(repo) == head  # detached
    assert harness.git_commit(tmp_path / "none") is None


# --- the general and previous sections: configs, runs' order, verdicts, report ------------


def test_general_section_configs_are_the_lines_asked_for():
    """The random line: masses and stiffnesses in [1, 10) from fixed seeds (the same
    line in every bench); the steel line: SI units, Hertz, the paper line's events."""
    (spec,) = parse_experiment(harness.config_text("g", 500, 1, 1.5, chain=harness.RANDOM_LINE),
                               "toml").runs()
    line = spec.line
    for a in (line.mass, line.stiffness):
        assert a.min() >= 1.0 and a.max() < 10.0 and a.max() / a.min() > 5
    (again,) = parse_experiment(harness.config_text("g", 500, 1, 1.5, chain=harness.RANDOM_LINE),
                                "toml").runs()
    assert np.array_equal(again.line.mass, line.mass)
    assert not np.array_equal(line.mass, line.stiffness)
    assert spec.t_end is None and line.velocity[0] == 1.0 and not line.velocity[1:].any()

    text = harness.config_text("s", 100, 1, None, top={"units": "si"}, chain=harness.SI_LINE)
    (si,) = parse_experiment(text, "toml").runs()
    assert si.units == "si" and si.line.velocity[0] == 0.5
    assert np.allclose(si.line.alpha, 1.5) and si.t_end is None


class _FakeProcs:
    """Stands for ``Processes``: records the order of runs, fails when told to."""

    def __init__(self, fail_at=None):
        self.order, self.fail_at = [], fail_at

    def run(self, text, *, env=None, timeout=None, read_velocity=True,
            read_diagnostics=False):
        self.order.append(text)
        if len(self.order) == self.fail_at:
            return harness.ProcessRun(None, None, None, error="exit status 1: boom")
        return harness.ProcessRun(float(len(self.order)), 1.0, 10.0,
                              diagnostics={"events": 1} if read_diagnostics else None)


def test_alternate_interleaves_the_runs_and_stops_at_a_failure():
    procs = _FakeProcs()
    out = harness.alternate(procs, {"a": {"text": "A"}, "b": {"text": "B"}}, 3)
    assert procs.order == ["A", "B"] * 3
    assert out["a"]["walls"] == [1.0, 3.0, 5.0] and out["b"]["walls"] == [2.0, 4.0, 6.0]
    assert harness.ratio(out["b"], out["a"]) == pytest.approx(4.0 / 3.0)
    assert harness.ratio(out["b"], out["a"], min) == 2.0

    procs = _FakeProcs(fail_at=4)
    out = harness.alternate(procs, {"a": {"text": "A"}, "b": {"text": "B"}}, 3)
    assert procs.order == ["A", "B", "A", "B"]
    assert out["b"]["errors"] and out["b"]["walls"] == [2.0]
    assert harness.ratio(out["a"], {"walls": []}) is None


def _runs(walls, **diag):
    return {"walls": walls, "cpus": walls, "errors": [], "diagnostics": diag or None}


def test_general_verdict_measured_predicted_or_not_at_all():
    uni = _runs([1.0, 1.2, 1.1])
    measured = {"n": 10**6, "uniform": uni, "random": _runs([2.0]), "ratio": 2.0 / 1.1}
    assert general.verdict(measured) == {"n": 10**6, "ratio": 2.0 / 1.1,
                                              "measured": True, "met": True}
    predicted = {"n": 10**6, "uniform": uni, "ratio": None, "random_predicted": 11.0}
    v = general.verdict(predicted)
    assert not v["measured"] and v["ratio"] == pytest.approx(10.0) and v["met"] is False
    assert general.verdict({"n": 5, "uniform": uni, "ratio": None})["met"] is None


def _general_result():
    diag = dict(events=299, steps=725, rejected_steps=5, max_window=12, outcome="terminal")
    rdiag = dict(events=24259, steps=125799, rejected_steps=111800, max_window=220,
                 outcome="terminal")
    series = [{"n": 300, "uniform": _runs([0.72, 0.73, 0.71], **diag),
               "random": _runs([2.27, 2.23, 2.25], **rdiag), "ratio": 2.25 / 0.72},
              {"n": 10**6, "uniform": _runs([7.4, 7.6, 7.5], **diag),
               "random_skipped": "predicted solver time 1e+07 s > 60 s (--full for more)",
               "random_predicted": 7.5e6, "ratio": None}]
    units = {"n": 10**5, "si_line": harness.SI_LINE, "paper": _runs([0.95, 0.97, 0.96], **diag),
             "si": _runs([0.96, 0.94, 0.98], **diag), "ratio": 1.0, "same_work": True}
    g = {"random_line": harness.RANDOM_LINE, "limit": 2.0, "requirement_n": 10**6, "runs": 3,
         "series": series, "units": units}
    g["requirement"] = general.verdict(series[-1])
    return g


def _previous_result():
    new, old = _runs([0.70, 0.72, 0.69]), _runs([0.75, 0.74, 0.76])
    return {"runs": 3, "commit": "a" * 40, "asked": None, "subject": "Faster heap",
            "why": "bbbbbbbbbbbb^, the solver before its latest change (\"x\")",
            "new": {"commit": "c" * 40, "solver_changes_uncommitted": False},
            "old_first_run": {"wall": 40.7, "cpu": 40.1, "warm_wall": 0.8, "error": None},
            "cases": [{"label": "Hertz", "n": 10_000, "alpha": 1.5, "new": new, "old": old,
                       "ratio_median": 0.70 / 0.75, "ratio_min": 0.69 / 0.74}]}


def test_report_shows_the_general_and_previous_sections():
    meta = {"machine": {"machine": "x86_64", "cpus": 2, "memory_gb": 24}, "mode": "default",
            "date": "2026-11-24T08:00:00", "git_commit": "c" * 40, "load_start": (1.0,),
            "load_end": (1.0,), "total_time": 1.0, "json": "b.json"}
    done = {"general": general.GeneralResult(**_general_result()),
            "previous": previous.PreviousResult(**_previous_result())}
    text = run.report(meta, done, [])
    # every time is printed, with the medians and the ratio to the paper's line
    assert "0.72, 0.73, 0.71" in text and "2.27, 2.23, 2.25" in text
    assert re.search(r"random\s+2\.27, 2\.23, 2\.25\s+2\.25\s+3\.12\s+24259\s+125799", text)
    assert "random N = 1000000: predicted solver time" in text
    assert ("Requirement random <= 2 x uniform at N = 1000000: NOT MET by prediction"
            in text)
    assert "si / paper: 1.00 x; events and steps the same (299 and 725)" in text
    # the previous version: which, why, its compilation left out, min/median, ratios
    assert 'Previous version: aaaaaaaaaaaa "Faster heap", chosen as bbbbbbbbbbbb^' in text
    assert "took 40.7 s (cpu 40.1 s), 0.80 s warm: left out" in text
    assert re.search(r"Hertz 10000\s+0\.69\s+0\.70\s+0\.74\s+0\.75\s+0\.93\s+0\.93", text)
    assert "Hertz N = 10000: new 0.70, 0.72, 0.69 s; old 0.75, 0.74, 0.76 s" in text

    measured = _general_result()
    last = measured["series"][-1]
    last.update(random=_runs([9.0, 9.5, 9.2]), ratio=9.2 / 7.5)
    measured["requirement"] = general.verdict(last)
    assert any(line.endswith("MET (1.23 x)") and "NOT" not in line
               for line in general.GeneralResult(**measured).lines())
    assert previous.PreviousResult(cases=[], error="cannot resolve").lines() == [
        "Previous version: cannot resolve"]


# --- the targets: issue 34's lines, their runs' events, the no-slower target --------------


def test_targets_are_the_lines_of_issue_34():
    """The default targets: the K = 80 cascade, the random line, the damped steel line
    (the lammps section's), Hertz 10^6 and linear 10^5, each with its limit; Hertz 10^4
    no slower than the previous version, which runs the random and damped lines too."""
    mode = run.Mode.make(full=False)
    assert [(c.name, c.limit) for c in mode.targets] == [
        ("Hertz N = 2000, K = 80", 10.0), ("random N = 1000", 3.0), ("damped N = 3000", 5.0),
        ("Hertz N = 1000000", 5.0), ("linear N = 100000", 3.0)]
    k80, rand, damped = (parse_experiment(c.config("t"), "toml").runs()[0]
                         for c in mode.targets[:3])
    assert (k80.n, k80.k, k80.alpha, k80.t_end) == (2000, 80, 1.5, None)
    assert rand.line.mass.min() >= 1.0 and rand.line.mass.max() < 10.0 and rand.k == 1
    (same,) = parse_experiment(harness.config_text("g", 1000, 1, 1.5,
                                                   chain=harness.RANDOM_LINE), "toml").runs()
    assert np.array_equal(rand.line.mass, same.line.mass)
    assert np.array_equal(rand.line.stiffness, same.line.stiffness)
    assert damped.units == "si" and damped.n == 3000 and damped.t_end is None
    assert np.all(damped.line.damping > 0) and np.allclose(damped.line.damping_exponent, 0.25)
    from benchmarks import against_lammps
    assert harness.DAMPED_LINE == against_lammps.LINES["damped"]
    assert [(c.name, c.no_slower) for c in mode.previous_cases] == [
        ("Hertz N = 10000", True), ("Hertz N = 1000000", False),
        ("linear N = 100000", False), ("random N = 1000", False), ("damped N = 3000", False)]
    smoke = run.Mode.make(full=False, smoke=True)             # small sizes, the same lines
    assert [c.label for c in smoke.targets] == [c.label for c in mode.targets]
    assert max(c.n for c in smoke.targets) <= 2000


class _ScriptedProcs:
    """Stands for ``Processes``: each config's runs take the walls given, in order, and
    end as the diagnostics say."""

    def __init__(self, walls: dict, outcome="terminal"):
        self.walls, self.outcome, self.texts = walls, outcome, []

    def run(self, text, *, env=None, timeout=None, read_velocity=True,
            read_diagnostics=False):
        self.texts.append(text)
        key = next(k for k in self.walls if f"-{k}" in text.splitlines()[0])
        wall = self.walls[key].pop(0)
        d = {"events": 1000, "steps": 3000, "rejected_steps": 700, "max_window": 50,
             "closed_form_collisions": 0, "outcome": self.outcome, "end_time": 9.0}
        return harness.ProcessRun(wall, wall, 100.0,
                                  diagnostics=d if read_diagnostics else None)


def test_targets_section_reports_each_run_its_events_and_verdict():
    mode = run.Mode(full=False, target_runs=3, target_over=3.0,
                    targets=(harness.Case("Hertz", 2000, k=80, limit=10.0),
                             harness.Case.random(1000, limit=3.0)))
    procs = _ScriptedProcs({"hertz-2000-k80": [31.0, 1.0, 1.0], "random-1000": [2.0, 2.5, 3.5]})
    ctx = harness.Context(mode, procs)
    got = targets.run(ctx)
    k80, rand = got.targets
    # the cascade's first run is over 3x its limit: not repeated, not met
    assert k80.walls == [31.0] and not k80.met and k80.stopped
    assert (rand.walls, rand.runs_within_limit, rand.met) == ([2.0, 2.5, 3.5], 2, False)
    assert rand.events == [1000] * 3 and rand.per_event_us() == [2000.0, 2500.0, 3500.0]
    text = "\n".join(got.lines())
    assert ("Hertz N = 2000, K = 80: 31.0 s (limit 10 s): NOT MET, met in 0 of 1 runs "
            "(not repeated: over 3 x the limit); 1,000 events, 31,000 us per event" in text)
    assert "random N = 1000: 2.00, 2.50, 3.50 s (limit 3 s): NOT MET, met in 2 of 3" in text
    assert "3,000 steps (700 rejected), window up to 50 balls" in text
    assert "Hertz N = 10000: no slower than the previous version" in text
    assert "random: masses and stiffnesses uniform in [1, 10)" in text
    assert targets.TargetsResult.from_json(got.to_json()).lines() == got.lines()
    # a run that ends short of the terminal state is not a time of the target
    procs = _ScriptedProcs({"hertz-2000-k80": [1.0], "random-1000": [1.0]}, outcome="stop_time")
    got = targets.run(harness.Context(mode, procs))
    assert all(not t.met and not t.walls and "not in the terminal state" in t.errors[0]
               for t in got.targets)


def test_previous_section_runs_the_cases_and_reads_the_no_slower_target():
    mode = run.Mode.make(full=False, smoke=True)
    mode.previous_runs = 2
    names = ["warmup"] + [c.config("previous").splitlines()[0] for c in mode.previous_cases]

    class Procs:
        texts = []

        def run(self, text, *, env=None, timeout=None, read_velocity=True,
                read_diagnostics=False):
            self.texts.append(text)
            # the old version 10% slower on Hertz 200, 10% faster on the others
            fast = "hertz-200\"" in text.splitlines()[0]
            wall = {"new": 1.0, "old": 1.1 if fast else 0.9}[env["who"]]
            return harness.ProcessRun(wall, wall, 100.0)

    procs = Procs()
    out = previous.PreviousResult(runs=2, slack=mode.previous_slack, commit="a" * 40,
                                  why="HEAD", subject="s")
    previous._compare(out, mode, procs, {"new": {"who": "new"}, "old": {"who": "old"}})
    assert [c["label"] for c in out.cases] == ["Hertz", "Hertz", "linear", "random", "damped"]
    firsts = [t.splitlines()[0] for t in procs.texts]
    for name in names[1:]:
        assert firsts.count(name) == 4                      # 2 runs x 2 versions
    assert out.cases[0]["no_slower"] and out.cases[0]["ratio_median"] == pytest.approx(1 / 1.1)
    text = "\n".join(out.lines())
    assert ("Target Hertz N = 200 no slower than the previous version (new/old median at "
            "most 1.05): MET (new/old median 0.91)") in text
    assert re.search(r"damped 100\s+1\.00\s+1\.00\s+0\.90\s+0\.90\s+1\.11", text)
    assert "damped: steel beads of one inch in SI units" in text
    slower = dict(out.cases[0], ratio_median=1.2)
    assert out.verdict(slower) == "NOT MET (new/old median 1.20)"
    assert out.verdict(out.cases[1]) is None


def test_a_process_run_reads_its_events_from_the_run_file(tmp_path):
    """The targets' events come from the run file's diagnostics (a real process)."""
    r = harness.Processes(tmp_path).run(harness.Case.damped(20).config("t"),
                                        read_velocity=False, read_diagnostics=True)
    assert r.error is None and r.wall > 0
    assert r.diagnostics["outcome"] == "terminal" and r.diagnostics["events"] > 0
    assert r.diagnostics["steps"] >= r.diagnostics["rejected_steps"] >= 0


@pytest.fixture
def solver_history(tmp_path):
    """A repository whose solver changed in commits 1 and 2, and docs alone in 3."""
    if shutil.which("git") is None:
        pytest.skip("git is not installed")
    repo = tmp_path / "repo"
    (repo / "chainrun" / "solver").mkdir(parents=True)
    env = ["-c", "user.name=t", "-c", "user.email=t@t"]
    _git("init", "-q", cwd=repo)
    commits = []
    for i, path in enumerate(["chainrun/solver/a.py", "chainrun/solver/a.py", "README"]):
        (repo / path).write_text(str(i))
        _git("add", path, cwd=repo)
        _git(*env, "commit", "-q", "-m", f"change {i}", cwd=repo)
        commits.append(_git("rev-parse", "HEAD", cwd=repo))
    return repo, commits


def test_previous_version_is_the_solver_before_its_latest_change(solver_history):
    repo, (c0, c1, c2) = solver_history
    got = worktree.resolve_against(None, repo, environ={})
    assert got["commit"] == c0 and got["subject"] == "change 0"
    assert got["why"].startswith(f"{c1[:12]}^") and "change 1" in got["why"]
    # named: by the option, else the environment variable
    assert worktree.resolve_against("HEAD~1", repo, environ={})["commit"] == c1
    env = {worktree.AGAINST_ENV: "HEAD"}
    assert worktree.resolve_against(None, repo, environ=env)["commit"] == c2
    assert worktree.resolve_against("HEAD~2", repo, environ=env)["commit"] == c0
    with pytest.raises(ValueError, match="no-such-rev"):
        worktree.resolve_against("no-such-rev", repo, environ={})
    # uncommitted solver changes: this version is the work tree, the previous one HEAD
    (repo / "chainrun" / "solver" / "a.py").write_text("new")
    got = worktree.resolve_against(None, repo, environ={})
    assert got["commit"] == c2 and "uncommitted" in got["why"]


def test_previous_version_needs_a_parent(tmp_path):
    if shutil.which("git") is None:
        pytest.skip("git is not installed")
    repo = tmp_path / "repo"
    (repo / "chainrun" / "solver").mkdir(parents=True)
    _git("init", "-q", cwd=repo)
    (repo / "chainrun" / "solver" / "a.py").write_text("0")
    _git("add", ".", cwd=repo)
    _git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "0", cwd=repo)
    with pytest.raises(ValueError, match="no parent"):
        worktree.resolve_against(None, repo, environ={})
    other = tmp_path / "other"                               # no solver history at all
    other.mkdir()
    _git("init", "-q", cwd=other)
    (other / "README").write_text("x")
    _git("add", ".", cwd=other)
    _git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "0", cwd=other)
    with pytest.raises(ValueError, match="no commit changed"):
        worktree.resolve_against(None, other, environ={})


# --- the results file, and the numbers README.md quotes from it -------------------------


def test_readme_quotes_the_results_file():
    """README.md's measured numbers are the block the bench writes from
    benchmarks/results.json, and results.md is that file rendered: neither can drift
    from what was measured."""
    from benchmarks import results

    data = results.load()
    assert {"peers", "targets", "compile"} <= set(data["sections"])
    text = results.README.read_text()
    assert text.count(results.BEGIN) == 1 and text.count(results.END) == 1
    assert results.readme_text(text, data) == text
    assert results.markdown_path(results.RESULTS).read_text() == results.render(data)


def test_a_section_replaces_its_own_entry_and_keeps_the_others(tmp_path):
    from benchmarks import results
    from benchmarks.sections.compilation import CompileResult
    from benchmarks.sections.targets import Target, TargetsResult

    meta = {"git_commit": "c" * 40, "mode": "default",
            "machine": {"cpu": "x", "machine": "x86_64", "cpus": 2, "memory_gb": 24},
            "versions": {"chainrun": "0"}}
    path = tmp_path / "results.json"

    def put(name, result):
        return results.update(path, name, results.entry(
            result, meta=meta, date="2026-11-24T08:00:00", load_start=(1.5, 1, 1),
            load_end=(2.5, 1, 1), wall=3.0, notes=["a note"]))

    targets = TargetsResult([Target("Hertz", 10**6, 1.5, 10.0, walls=[7.5, 8.0, 7.9],
                                    cpus=[7.0, 7.1, 7.2], runs_within_limit=3, met=True)])
    put("targets", targets)
    put("compile", CompileResult(cold_wall=80.0, warm_wall=0.7, compile_wall=79.3,
                                 compile_cpu=78.0, numba_floor=[0.5, 0.6]))
    data = put("targets", TargetsResult([Target("linear", 10**5, 1.0, 30.0, walls=[3.0])]))
    assert list(data["sections"]) == ["compile", "targets"]       # the sections' order
    assert results.result_of(data, "targets").targets[0].label == "linear"
    assert results.result_of(data, "compile").compile_wall == 79.3
    # a result read back renders as it did when measured
    load = results.load(path)
    measured = CompileResult(cold_wall=80.0, warm_wall=0.7, compile_wall=79.3,
                             compile_cpu=78.0, numba_floor=[0.5, 0.6])
    assert results.result_of(load, "compile").lines() == measured.lines()
    md = results.markdown_path(path).read_text()
    assert md == results.render(load)
    assert "load average 1.5 at the start, 2.5 at the end" in md and "Note: a note" in md
    block = " ".join(results.readme_block(load).split())
    assert "a linear line of 10^5 balls in 3.00 s (limit 30 s)" in block
    assert "compiles the solver in 79 s" in block and "0.50-0.60 s" in block
    assert "load average 1.5 to 2.5" in block


def test_the_readme_quotes_the_ratios_to_lammps_against_their_targets():
    from benchmarks import results
    from benchmarks.against_lammps import LammpsResult

    meta = {"git_commit": "c" * 40, "mode": "default",
            "machine": {"cpu": "x", "machine": "x86_64", "cpus": 2, "memory_gb": 24},
            "versions": {"chainrun": "0"}}
    cost = [dict(kind="elastic", n=2000, ratio=91.4, target=None, met=None,
                 lammps={"measured": True}),
            dict(kind="elastic", n=10_000, ratio=2403.6, target=200.0, met=True,
                 lammps={"measured": False}),
            dict(kind="damped", n=3000, ratio=6.64, target=20.0, met=False,
                 lammps={"measured": True})]
    data = {"sections": {"lammps": results.entry(
        LammpsResult(cost=cost), meta=meta, date="2026-11-24T08:00:00",
        load_start=(1.0, 1, 1), load_end=(1.0, 1, 1), wall=3.0, notes=[])}}
    block = " ".join(results.readme_block(data).split())
    # the lines with a target only, each against it, and whether LAMMPS's time was measured
    assert ("faster by 2,404x on the elastic line of 10^4 balls (target 200x; LAMMPS "
            "extrapolated) and 6.6x on the damped line of 3000 balls (target 20x, not "
            "met), whole processes") in block
    assert "2000 balls" not in block


def test_the_solver_is_called_in_one_place():
    """Every benchmark runs chainrun's solver through ``harness.solve``: a change of
    the solver's entry point is adapted there. ``same_answers`` calls the solver of
    whichever revision it runs in, by that revision's name for it."""
    import ast
    from pathlib import Path

    root = Path(harness.__file__).resolve().parents[1]
    files = sorted((root / "benchmarks").rglob("*.py"))
    files += [root / "tests" / "integration" / "test_benchmarks.py",
              root / "tests" / "integration" / "test_lammps_peer.py"]
    allowed = {root / "benchmarks" / "harness.py", root / "benchmarks" / "same_answers.py"}
    calling = set()
    for path in files:
        for node in ast.walk(ast.parse(path.read_text())):
            if (isinstance(node, ast.ImportFrom) and (node.module or "").startswith(
                    "chainrun.solver") and {"simulate", "simulate_line"}
                    & {a.name for a in node.names}):
                calling.add(path)
            elif isinstance(node, ast.Attribute) and node.attr == "simulate_line":
                calling.add(path)
    assert calling <= allowed, sorted(str(p.relative_to(root)) for p in calling - allowed)
    assert root / "benchmarks" / "harness.py" in calling


def test_the_harness_imports_run_one_way():
    """peers <- harness <- worktree <- sections <- results <- run: a section imports
    the shared helpers and no part above it, and the helpers import no section."""
    import ast
    from pathlib import Path

    root = Path(harness.__file__).resolve().parents[1]
    rank = {"benchmarks.peers": 0, "benchmarks.harness": 1, "benchmarks.worktree": 2,
            "benchmarks.sections": 3, "benchmarks.against_lammps": 3,
            "benchmarks.results": 4, "benchmarks.run": 5}

    def part(name):
        while name and name not in rank:
            name = name.rpartition(".")[0]
        return name or None

    wrong = []
    for path in sorted((root / "benchmarks").rglob("*.py")):
        rel = path.relative_to(root).with_suffix("")
        name = ".".join(rel.parts[:-1] if rel.name == "__init__" else rel.parts)
        src = part(name)
        if src is None:
            continue                                    # a script of its own
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                targets = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                continue
            for target in targets:
                dst = part(target)
                if dst is not None and dst != src and rank[dst] > rank[src]:
                    wrong.append((name, target))
    assert not wrong, wrong


def test_steered_section_judges_by_what_rounding_does_not_move(monkeypatch):
    """Two runs whose velocities differ ball by ball but not in their statistics meet
    the tolerance they set (MARGIN x their spread); a later run is judged by the
    recorded tolerance, and a broken balance or a state that is not terminal fails."""
    from types import SimpleNamespace

    from benchmarks.sections import steered

    n = 200
    base = np.linspace(-0.2, 1.0, n)
    finals = {1e-12: base, 1e-13: base + 1e-6 * np.linspace(0, 1, n)}
    broken = {"energy": 0.0, "order": False}

    def fake_solve(line, times=(), *, rtol=None, timeout=None, **kwargs):
        v = finals[rtol].copy()
        if broken["order"]:
            v[[5, 6]] = v[[6, 5]] + np.array([0.0, -0.01])
        x = 1e3 * v - np.arange(n) * 1e-3           # every contact open
        d = SimpleNamespace(events=10, momentum_error=1e-14,
                            energy_error=broken["energy"] or 2e-13, velocity_floor=rtol)
        return SimpleNamespace(final_position=x, final_velocity=v, end_time=1e3,
                               outcome=SimpleNamespace(value="terminal"), diagnostics=d)

    monkeypatch.setattr(steered, "solve", fake_solve)
    mode = run.Mode(full=False, steered=(harness.Case("Hertz", n, k=4),),
                    steered_timeout=None)
    got = steered.run(harness.Context(mode, None))
    (e,) = got.lines_run
    # terminal states are sorted along the line: the sorted profile's largest
    # difference is the ball-by-ball one
    assert e["max_dv"] == e["spread"]["sorted_max"] == pytest.approx(1e-6)
    assert e["spread"]["sorted_mean"] == pytest.approx(0.5e-6) and e["met"]
    assert all(r["terminal"] and r["balanced"] for r in e["runs"])
    assert e["spread"]["backwards"] == 0 and e["runs"][0]["stats"]["backwards"] == 34
    tol = e["tolerance"]
    assert tol["fastest"] == pytest.approx(steered.MARGIN * 1e-6)
    assert tol["p50"] == steered.FLOOR or tol["p50"] >= steered.MARGIN * e["spread"]["p50"]
    text = "\n".join(got.lines())
    assert "Hertz N = 200, K = 4: MET" in text and "tolerance from this run" in text
    data = got.to_json()
    assert "final_velocity" not in str(data)
    assert steered.SteeredResult.from_json(data).lines() == got.lines()
    # a later run reads the tolerance recorded, and compares with the recorded stats
    recorded = {"steered": {"result": data, "date": "2026-11-27T16:00:00",
                            "commit": "a" * 40}}
    broken["energy"] = 1e-8
    again = steered.run(harness.Context(mode, None, recorded=recorded))
    (e2,) = again.lines_run
    assert e2["tolerance"] == tol and e2["against_recorded"]["fastest"] == 0.0
    assert "2026-11-27T16:00:00, commit aaaaaaaaaaaa" in e2["tolerance_from"]
    assert e2["within"] and not e2["met"] and not e2["runs"][0]["balanced"]
    assert steered.failures(e2) == ["rtol 1e-12: energy 1.0e-08 > 1e-10",
                                    "rtol 1e-13: energy 1.0e-08 > 1e-10"]
    assert "NOT MET (rtol 1e-12: energy 1.0e-08 > 1e-10;" in "\n".join(again.lines())
    broken.update(energy=0.0, order=True)
    e3 = steered.run(harness.Context(mode, None, recorded=recorded)).lines_run[0]
    assert not e3["runs"][0]["terminal"] and not e3["met"]
    assert "rtol 1e-12: not terminal" in steered.failures(e3)
    assert "terminal NO" in "\n".join(steered.SteeredResult([e3]).lines())


def test_steered_section_on_tiny_lines():
    """Real runs: the terminal check agrees with the solver's, the balances hold."""
    from benchmarks.sections import steered

    mode = run.Mode.make(full=False, smoke=True)
    assert [c.label for c in mode.steered] == ["Hertz", "random"]
    mode.steered = (harness.Case("Hertz", 40, k=4), harness.Case.random(30))
    got = steered.run(harness.Context(mode, None))
    for e in got.lines_run:
        assert not e.get("error")
        for r in e["runs"]:
            assert r["outcome"] == "terminal" and r["terminal"] and r["balanced"], r
        assert e["met"]


def test_the_steps_trace_adds_up_to_the_runs_counts():
    """benchmarks.steps reads the solver's counters at intervals of a run: over the
    whole run they add up to what the run's diagnostics count, and the ball-steps
    summed over the intervals never fall and stay within steps x widest window."""
    from benchmarks import steps
    from benchmarks.window import make_line

    line = make_line("damped", 40, 1)
    rows = steps.trace(line, 4, log=True)
    d = harness.solve(line).diagnostics
    assert len(rows) == 4
    assert rows[-1][1:4] == (d.steps, d.rejected_steps, d.events)
    assert [r[0] for r in rows] == sorted(r[0] for r in rows)
    assert all(a[6] <= b[6] for a, b in zip(rows, rows[1:]))  # ball-steps only grow
    assert rows[-1][6] <= d.steps * d.max_window
