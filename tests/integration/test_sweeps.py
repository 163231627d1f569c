"""Sweeps: resumption, failures, and Dask execution on a real scheduler over loopback.

The cluster tests start ``dask scheduler`` and two ``dask worker`` processes on
127.0.0.1 and run ``chainrun simulate`` as a separate process against them, so the
client, the scheduler and the workers are as separate as on a real cluster.
"""

from __future__ import annotations

import concurrent.futures as cf
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

import chainrun.runner as runner
from chainrun.runner import executors
from chainrun.cli import main
from chainrun.config import load_experiment
from chainrun.errors import ChainrunError
from chainrun.store import read_index, read_run, run_config_hash

SMALL = """\
name = "small"
[chain]
n = 5
k = 1
alpha = 1.5
[output]
times = [0.0, 1.0, 2.0]
[sweep]
"chain.k" = {ks}
"""

# Six runs of about 0.5-1 s each: long enough to kill something while they compute.
SLOW = """\
name = "slow"
[chain]
n = 200
k = 2
alpha = 1.5
[output]
times = [0.0, 10.0]
[sweep]
"chain.n" = [200, 210, 220, 230, 240, 250]
"""
SLOW_IDS = [f"n={n}" for n in (200, 210, 220, 230, 240, 250)]


#: Seconds a test waits for a sweep (generous: a cold numba cache compiles for a while).
PATIENCE = 600


@pytest.fixture(scope="module")
def warm_kernels():
    """Compile (or load) the solver's kernels once, before worker processes need them."""
    from chainrun.solver import Line, simulate

    simulate(Line.paper(20, 2, 1.5), np.array([0.0, 1.0]))


def write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def simulate_cli(*args: str, env=None):
    """``chainrun simulate ARGS`` in this process."""
    result = CliRunner(env=env).invoke(main, ["simulate", *map(str, args)])
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    return result


@pytest.fixture
def chainrun_process():
    """Start ``chainrun simulate ARGS`` as its own process (output captured).

    Each in its own process group, which the fixture kills at the end if it is still
    running (with any local workers it started).
    """
    started: list[subprocess.Popen] = []

    def start(*args, env_extra=None) -> subprocess.Popen:
        env = {k: v for k, v in os.environ.items() if k != runner.SCHEDULER_ENV}
        env.update(env_extra or {})
        proc = subprocess.Popen(
            [sys.executable, "-m", "chainrun", "simulate", *map(str, args)],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
            start_new_session=True,
        )
        started.append(proc)
        return proc

    yield start
    for proc in started:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()


def stamps(folder: Path) -> dict[str, tuple[int, int]]:
    """(inode, mtime) of each run file: unchanged when a run is skipped."""
    return {p.name: (p.stat().st_ino, p.stat().st_mtime_ns)
            for p in folder.glob("*.h5") if p.name != "index.h5"}


def partials(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if ".partial-" in p.name)


def assert_index_whole(outdir: Path, config: Path, run_ids: list[str]) -> None:
    """The index lists exactly these runs, and each link opens a file of this config."""
    specs = {s.run_id: s for s in load_experiment(config).runs()}
    rows = read_index(outdir / "index.h5")
    assert [r["run_id"] for r in rows] == run_ids
    with h5py.File(outdir / "index.h5", "r") as index:
        for row in rows:
            spec = specs[row["run_id"]]
            assert row["config_hash"] == spec.config_hash
            assert run_config_hash(outdir / row["file"]) == spec.config_hash
            final = index[f"runs/{row['run_id']}/results/final_velocity"][()]
            assert final.shape == (spec.n,)
    assert partials(outdir) == []


# ------------------------------------------------------------------ store helper


def test_run_config_hash_trusts_only_whole_run_files(tmp_path):
    config = write(tmp_path / "small.toml", SMALL.format(ks="[1]"))
    assert simulate_cli(config, "-o", tmp_path / "out").exit_code == 0
    good = tmp_path / "out" / "k=1.h5"
    assert run_config_hash(good) == load_experiment(config).runs()[0].config_hash

    raw = good.read_bytes()
    (tmp_path / "truncated.h5").write_bytes(raw[: len(raw) // 2])
    (tmp_path / "text.h5").write_text("not HDF5")
    with h5py.File(tmp_path / "foreign.h5", "w") as h5:
        h5.create_group("parameters").attrs["config_hash"] = "abc"
    for name in ("truncated.h5", "text.h5", "foreign.h5", "missing.h5"):
        assert run_config_hash(tmp_path / name) is None, name
    assert run_config_hash(tmp_path / "out" / "index.h5") is None


# ------------------------------------------------------------ resuming in-process


def test_runs_whose_file_matches_are_skipped(tmp_path):
    config = write(tmp_path / "small.toml", SMALL.format(ks="[1, 2, 3]"))
    out = tmp_path / "out"
    first = simulate_cli(config, "-o", out)
    assert first.exit_code == 0, first.output
    before = stamps(out)

    again = simulate_cli(config, "-o", out)
    assert again.exit_code == 0, again.output
    assert again.stdout.count("skipped, file up to date") == 3
    assert "0 computed" in again.stderr and "3 skipped" in again.stderr
    assert stamps(out) == before
    assert_index_whole(out, config, ["k=1", "k=2", "k=3"])
    # The velocity table is the same whether computed or read back.
    assert first.stdout.split("final velocities")[1] == again.stdout.split("final velocities")[1]


def test_a_changed_config_reruns_only_what_it_changes(tmp_path):
    config = write(tmp_path / "small.toml", SMALL.format(ks="[1, 2]"))
    out = tmp_path / "out"
    assert simulate_cli(config, "-o", out).exit_code == 0
    before = stamps(out)

    write(config, SMALL.format(ks="[1, 2, 3]"))  # one more run: no --force needed
    grown = simulate_cli(config, "-o", out)
    assert grown.exit_code == 0, grown.output
    assert "1 computed" in grown.stderr and "2 skipped" in grown.stderr
    assert {k: v for k, v in stamps(out).items() if k in before} == before
    assert_index_whole(out, config, ["k=1", "k=2", "k=3"])

    # k=2.h5 now holds another run's config: only that run is in conflict.
    shutil.copy(out / "k=1.h5", out / "k=2.h5")
    before = stamps(out)
    refused = simulate_cli(config, "-o", out)
    assert refused.exit_code == 2
    assert "k=2.h5" in refused.stderr and "--force" in refused.stderr
    # what differs, from the file's own config against the run's
    assert "(k=2.h5: chain.k is 1 in k=2.h5, 2 here)" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 2  # the banner and one error line
    assert stamps(out) == before

    (out / "figures").mkdir()  # drawn from the runs replaced now: said to be stale
    forced = simulate_cli(config, "-o", out, "--force")
    assert forced.exit_code == 0, forced.output
    assert "figures holds the figures of the runs replaced now" in forced.stderr
    assert "1 computed" in forced.stderr and "2 skipped" in forced.stderr
    after = stamps(out)
    assert after["k=1.h5"] == before["k=1.h5"] and after["k=3.h5"] == before["k=3.h5"]
    assert after["k=2.h5"] != before["k=2.h5"]
    assert_index_whole(out, config, ["k=1", "k=2", "k=3"])


def test_stale_partial_files_and_foreign_files(tmp_path):
    config = write(tmp_path / "small.toml", SMALL.format(ks="[1, 2]"))
    out = tmp_path / "out"
    out.mkdir()
    (out / ".k=1.h5.partial-999999").write_bytes(b"\x89HDF half a file")
    (out / "k=2.h5").write_text("someone else's file")

    refused = simulate_cli(config, "-o", out)
    assert refused.exit_code == 2 and "k=2.h5" in refused.stderr
    assert (out / "k=2.h5").read_text() == "someone else's file"

    forced = simulate_cli(config, "-o", out, "--force")
    assert forced.exit_code == 0, forced.output
    assert_index_whole(out, config, ["k=1", "k=2"])  # includes: no partial file left


def test_an_interrupted_sweep_resumes_and_loses_no_finished_run(tmp_path, monkeypatch):
    config = write(tmp_path / "small.toml", SMALL.format(ks="[1, 2, 3, 4]"))
    out = tmp_path / "out"
    real = runner.simulate_run

    def interrupted_in_k3(spec, outdir, **kwargs):
        if spec.run_id != "k=3":
            return real(spec, outdir, **kwargs)

        def ctrl_c(run_id, t):  # in the middle of writing k=3's file
            if t > 0.5:
                raise KeyboardInterrupt
        return real(spec, outdir, on_progress=ctrl_c)

    monkeypatch.setattr(runner, "simulate_run", interrupted_in_k3)
    result = simulate_cli(config, "-o", out)
    assert result.exit_code == 130
    assert "the same command resumes" in result.stderr
    assert sorted(stamps(out)) == ["k=1.h5", "k=2.h5"]
    assert not (out / "index.h5").exists() and partials(out) == []
    before = stamps(out)

    monkeypatch.setattr(runner, "simulate_run", real)
    resumed = simulate_cli(config, "-o", out)
    assert resumed.exit_code == 0, resumed.output
    assert "2 computed" in resumed.stderr and "2 skipped" in resumed.stderr
    assert {k: stamps(out)[k] for k in before} == before
    assert_index_whole(out, config, ["k=1", "k=2", "k=3", "k=4"])


def test_an_interrupted_sweep_removes_the_files_its_killed_workers_left(tmp_path,
                                                                       monkeypatch):
    # a local cluster's workers are killed on an interrupt, midway through writing;
    # their half-written files go, and a file another process writes stays
    config = write(tmp_path / "small.toml", SMALL.format(ks="[1, 2]"))
    out = tmp_path / "out"

    class Killed(cf.Executor):
        workers = "on two killed workers"
        killed: set = set()

        def submit(self, fn, /, *args, **kwargs):
            (out / ".k=1.h5.partial-4242").write_bytes(b"\x89HDF half")
            (out / ".k=2.h5.partial-4343").write_bytes(b"\x89HDF half")
            raise KeyboardInterrupt

        def shutdown(self, wait=True, *, cancel_futures=False):
            self.killed = {4242}

    monkeypatch.setattr(runner, "open_executor", lambda **kwargs: Killed())
    with pytest.raises(KeyboardInterrupt):
        runner.simulate_experiment(load_experiment(config), out, jobs=2)
    assert partials(out) == [".k=2.h5.partial-4343"]


def test_a_run_that_raises_does_not_stop_the_others(tmp_path, monkeypatch):
    config = write(tmp_path / "small.toml", SMALL.format(ks="[1, 2, 3]"))
    out = tmp_path / "out"
    real = runner.simulate_run

    def broken_k2(spec, outdir, **kwargs):
        if spec.run_id == "k=2":
            raise OSError("disk full")
        return real(spec, outdir, **kwargs)

    monkeypatch.setattr(runner, "simulate_run", broken_k2)
    result = runner.simulate_experiment(load_experiment(config), out)
    assert [r.run_id for r in result.failures] == ["k=2"]
    assert isinstance(result.failures[0], runner.RunError)
    assert result.failures[0].message == "OSError: disk full"
    assert_index_whole(out, config, ["k=1", "k=3"])  # a run without a file has no row

    monkeypatch.setattr(runner, "simulate_run", real)
    result = runner.simulate_experiment(load_experiment(config), out)
    assert not result.failures and len(result.skipped) == 2
    assert_index_whole(out, config, ["k=1", "k=2", "k=3"])


def test_local_processes_without_dask(tmp_path, monkeypatch):
    monkeypatch.setattr(executors, "dask_available", lambda: False)
    config = write(tmp_path / "small.toml", SMALL.format(ks="[1, 2, 3]"))
    result = runner.simulate_experiment(load_experiment(config), tmp_path / "out", jobs=2)
    assert result.workers == "on 2 local processes"
    assert not result.failures
    assert_index_whole(tmp_path / "out", config, ["k=1", "k=2", "k=3"])


def test_where_to_compute_is_checked_before_anything_runs(tmp_path, monkeypatch):
    config = write(tmp_path / "small.toml", SMALL.format(ks="[1]"))
    both = simulate_cli(config, "-o", tmp_path / "out", "--jobs", "2",
                        "--scheduler", "tcp://127.0.0.1:9")
    assert both.exit_code == 2 and "--jobs" in both.stderr
    assert not (tmp_path / "out").exists()
    monkeypatch.delenv(runner.SCHEDULER_ENV, raising=False)
    assert runner.open_executor().__class__ is runner.InlineExecutor
    assert runner.open_executor(jobs=4, runs=1).__class__ is runner.InlineExecutor
    monkeypatch.setattr(executors, "dask_available", lambda: False)
    with pytest.raises(ChainrunError, match=r"chainrun\[dask\]"):
        runner.open_executor(scheduler="tcp://127.0.0.1:9")


# ------------------------------------------------------------------- with Dask


def test_a_failed_run_is_reported_and_the_others_finish(tmp_path, warm_kernels,
                                                        chainrun_process):
    pytest.importorskip("distributed")
    config = write(tmp_path / "limits.toml", """\
name = "limits"
[chain]
n = 40
k = 2
alpha = 1.5
[output]
times = [0.0, 5.0]
[sweep]
"solver.max_events" = [3, 1000000]
""")
    out = tmp_path / "out"
    proc = chainrun_process(config, "-o", out, "--jobs", "2")
    stdout, stderr = proc.communicate(timeout=PATIENCE)
    assert proc.returncode == 1, stderr
    assert "on a local Dask cluster of 2 workers" in stderr
    assert "run max_events=3 failed: event limit (3) reached" in stderr
    assert "max_events=1000000: terminal at t" in stdout
    rows = {r["run_id"]: r for r in read_index(out / "index.h5")}
    assert rows["max_events=3"]["outcome"] == "event_limit"
    assert rows["max_events=1000000"]["outcome"] == "terminal"

    # The failed run's file matches its config: it is not recomputed, but the
    # sweep still reports it and still fails.
    again = simulate_cli(config, "-o", out, "--jobs", "2")
    assert again.exit_code == 1
    assert "0 computed" in again.stderr and "1 failed" in again.stderr
    assert "run max_events=3 failed" in again.stderr


@pytest.fixture
def dask_cluster(tmp_path, warm_kernels):
    """A scheduler and two single-threaded workers (w1, w2) on 127.0.0.1.

    Yields (address, scheduler file, client, {worker name: process}).
    """
    pytest.importorskip("distributed")
    from distributed import Client

    logs = tmp_path / "dask-logs"
    logs.mkdir()
    scheduler_file = tmp_path / "scheduler.json"
    procs: dict[str, subprocess.Popen] = {}

    def start(name, *args):
        log = open(logs / f"{name}.log", "w")
        procs[name] = subprocess.Popen([sys.executable, "-m", "dask", *args],
                                       stdout=log, stderr=subprocess.STDOUT,
                                       start_new_session=True, cwd=tmp_path)
        log.close()

    client = None
    try:
        start("scheduler", "scheduler", "--host", "127.0.0.1", "--port", "0",
              "--no-dashboard", "--dashboard-address", "127.0.0.1:0",  # its HTTP server
              "--scheduler-file", str(scheduler_file))
        for name in ("w1", "w2"):
            start(name, "worker", "--scheduler-file", str(scheduler_file),
                  "--host", "127.0.0.1", "--nworkers", "1", "--nthreads", "1",
                  "--no-dashboard", "--name", name, "--death-timeout", "60")
        client = Client(scheduler_file=str(scheduler_file), timeout=30,
                        set_as_default=False)
        client.wait_for_workers(2, timeout=120)
        yield client.scheduler.address, scheduler_file, client, procs
    finally:
        if client is not None:
            client.close()
        for proc in procs.values():
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=30)


def _worker_address(client, name: str) -> str | None:
    for address, info in client.scheduler_info(n_workers=-1)["workers"].items():
        if info.get("name") == name:
            return address
    return None


def test_cluster_sweep_survives_a_killed_worker(tmp_path, dask_cluster, chainrun_process):
    address, _, client, procs = dask_cluster
    config = write(tmp_path / "slow.toml", SLOW)
    out = tmp_path / "out"
    sweep = chainrun_process(config, "-o", out, "--scheduler", address)

    victim = _worker_address(client, "w2")
    deadline = time.monotonic() + PATIENCE
    while not client.processing(workers=[victim]).get(victim):  # w2 is computing a run
        assert sweep.poll() is None and time.monotonic() < deadline, sweep.communicate()
        time.sleep(0.05)
    os.killpg(procs["w2"].pid, signal.SIGKILL)

    stdout, stderr = sweep.communicate(timeout=PATIENCE)
    assert sweep.returncode == 0, stderr
    assert "6 computed on the Dask scheduler at tcp://127.0.0.1:" in stderr
    assert list(client.scheduler_info(n_workers=-1)["workers"]) != [] and \
        _worker_address(client, "w2") is None
    assert sorted(line.split(":")[0] for line in stdout.splitlines() if "terminal at" in line) \
        == sorted(SLOW_IDS)
    assert_index_whole(out, config, SLOW_IDS)
    for run_id in SLOW_IDS:
        assert read_run(out / f"{run_id}.h5").terminal


def test_cluster_sweep_resumes_after_a_killed_client(tmp_path, dask_cluster, chainrun_process):
    address, scheduler_file, _, _ = dask_cluster
    config = write(tmp_path / "slow.toml", SLOW)
    out = tmp_path / "out"
    # The scheduler from the environment variable, as Dask users set it.
    sweep = chainrun_process(config, "-o", out, env_extra={runner.SCHEDULER_ENV: address})
    deadline = time.monotonic() + PATIENCE
    while len(stamps(out) if out.exists() else {}) < 2:
        assert sweep.poll() is None and time.monotonic() < deadline, sweep.communicate()
        time.sleep(0.02)
    sweep.kill()  # the client dies at once: no cleanup, no index
    sweep.communicate()
    finished = stamps(out)
    assert 2 <= len(finished) < len(SLOW_IDS)
    assert not (out / "index.h5").exists()

    resumed = chainrun_process(config, "-o", out, "--scheduler-file", scheduler_file)
    stdout, stderr = resumed.communicate(timeout=PATIENCE)
    assert resumed.returncode == 0, stderr
    skipped = [line.split(":")[0] for line in stdout.splitlines() if "skipped" in line]
    assert set(finished) <= {f"{s}.h5" for s in skipped}
    assert {k: stamps(out)[k] for k in finished} == finished  # not recomputed
    assert_index_whole(out, config, SLOW_IDS)
