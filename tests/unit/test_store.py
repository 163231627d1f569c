"""Run and index files: the schema of docs/schema.md, H5MD, netCDF dims, atomic writes.

The solutions here are built by hand (no solver): small N, a few snapshots and events.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
from pathlib import Path

import h5py
import numpy as np
import pytest

import chainrun
from chainrun import store
from chainrun.config import RunSpec
from chainrun.errors import StoreError
from chainrun.runner import observables, write_run
from chainrun.solver import Diagnostics, EventKind, Outcome, Solution

#: The observables of a line at rest where it started, for snapshots of zeros.
AT_REST = dict.fromkeys(store.OBSERVABLES, 0.0)

SCHEMA = Path(__file__).resolve().parents[2] / "docs" / "schema.md"

SOURCE = """\
name: cradle
chain: {n: 6, k: 2, alpha: 1.5}
output: {times: [0.0, 0.5, 1.5, 4.0]}
# a comment, kept: the file text is stored whole
"""


def make_spec(n=6, k=2, alpha=1.5, times=(0.0, 0.5, 1.5, 4.0), t_end=None,
              max_events=None, source_text=SOURCE) -> RunSpec:
    return RunSpec(
        experiment="cradle", run_id=f"k={k}", n=n, k=k, alpha=alpha,
        times=np.asarray(times, dtype=float), t_end=t_end, rtol=1e-12,
        max_events=max_events, overrides={"chain.k": k},
        config={"name": "cradle", "chain": {"n": n, "k": k, "alpha": alpha}},
        config_hash="0" * 63 + "1", source_text=source_text,
    )


def make_solution(spec: RunSpec, seed=0, events=5, keep_snapshots=True) -> Solution:
    rng = np.random.default_rng(seed)
    n, times = spec.n, np.asarray(spec.times)
    # compressions c_j = x_j - x_(j+1) of either sign
    x = -np.cumsum(rng.normal(0.05, 0.1, (len(times), n)), axis=1)
    v = rng.normal(0, 0.5, (len(times), n))
    sep_t = np.where(np.arange(n) % 3 == 0, np.nan, rng.random(n) * 10)
    diag = Diagnostics(steps=1234, rejected_steps=7, events=events, momentum_error=3e-16,
                       energy_error=-2e-15, energy_correction=4e-14, wall_time=0.25,
                       max_window=5, rtol=spec.rtol,
                       velocity_floor=1e-12)
    return Solution(
        n=n, k=spec.k, alpha=spec.alpha, outcome=Outcome.TERMINAL,
        message="terminal state at t = 12.5", end_time=12.5, terminal=True,
        final_position=rng.random(n), final_velocity=np.sort(rng.random(n)),
        separation_time=sep_t, separation_velocity=np.where(np.isnan(sep_t), np.nan, 0.3),
        event_time=np.sort(rng.random(events) * 12.5),
        event_contact=rng.integers(0, n - 1, events).astype(np.int64),
        event_kind=rng.choice([-2, -1, 1, 2], events).astype(np.int8),
        times=times, positions=x if keep_snapshots else None,
        velocities=v if keep_snapshots else None, diagnostics=diag,
    )


@pytest.fixture
def run(tmp_path):
    spec = make_spec()
    sol = make_solution(spec)
    path = tmp_path / "k=2.h5"
    write_run(path, spec, sol, velocity_floor=1e-12)
    return path, spec, sol


def attr_is_fixed_string(obj, name: str) -> bool:
    tid = h5py.h5a.open(obj.id, name.encode()).get_type()
    return isinstance(tid, h5py.h5t.TypeStringID) and not tid.is_variable_str()


def s(value) -> str:
    return value.decode() if isinstance(value, bytes) else str(value)


# ------------------------------------------------------------------------ the tree


def test_root_and_h5md_metadata(run):
    path, _, _ = run
    with h5py.File(path, "r") as f:
        assert f.attrs["format"] == "chainrun-run"
        assert f.attrs["format_version"] == 2
        assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\+00:00", f.attrs["created"])
        h5md = f["h5md"]
        assert h5md.attrs["version"].tolist() == [1, 1]
        assert np.issubdtype(h5md.attrs["version"].dtype, np.integer)
        assert s(h5md["author"].attrs["name"]) == (os.environ.get("USER") or "chainrun user")
        assert s(h5md["creator"].attrs["name"]) == "chainrun"
        assert s(h5md["creator"].attrs["version"]) == chainrun.__version__
        for group, name in [("author", "name"), ("creator", "name"), ("creator", "version")]:
            assert attr_is_fixed_string(h5md[group], name)
        box = f["particles/chain/box"]
        assert box.attrs["dimension"] == 1
        assert [s(b) for b in box.attrs["boundary"]] == ["none"]
        assert attr_is_fixed_string(box, "boundary")


def test_parameters(run, tmp_path):
    path, spec, _ = run
    with h5py.File(path, "r") as f:
        a = f["parameters"].attrs
        assert (a["n"], a["k"], a["alpha"]) == (6, 2, 1.5)
        assert a["n"].dtype == np.int64 and a["alpha"].dtype == np.float64
        assert np.isnan(a["t_end"]) and a["max_events"] == -1
        assert a["rtol"] == 1e-12 and a["velocity_floor"] == 1e-12
        assert (a["experiment"], a["run_id"]) == ("cradle", "k=2")
        assert a["config_hash"] == spec.config_hash
        assert a["config"] == SOURCE
        assert json.loads(a["config_resolved"]) == spec.config
        assert json.loads(a["overrides"]) == {"chain.k": 2}

    spec2 = make_spec(t_end=3.5, max_events=100)
    write_run(tmp_path / "b.h5", spec2, make_solution(spec2), velocity_floor=2e-12)
    params = store.read_run(tmp_path / "b.h5").parameters
    assert params["t_end"] == 3.5 and params["max_events"] == 100
    assert params["velocity_floor"] == 2e-12


def test_large_config_text_is_kept_whole(tmp_path):
    spec = make_spec(source_text=SOURCE + "# padding\n" * 20000)  # ~200 kB > 64 kB attribute limit
    write_run(tmp_path / "r.h5", spec, make_solution(spec), velocity_floor=1e-12)
    assert store.read_run(tmp_path / "r.h5").parameters["config"] == spec.source_text


def test_time_dependent_elements(run):
    path, spec, sol = run
    T, N = len(spec.times), spec.n
    with h5py.File(path, "r") as f:
        chain = f["particles/chain"]
        assert chain["ball"][:].tolist() == list(range(1, N + 1))
        assert chain["ball"].dtype == np.int64
        for name, expected in [("position", sol.positions), ("velocity", sol.velocities)]:
            el = chain[name]
            assert el["value"].shape == (T, N, 1) and el["value"].dtype == np.float64
            assert el["value"].maxshape == (None, N, 1)
            assert el["time"].dtype == np.float64 and el["step"].dtype == np.int64
            np.testing.assert_array_equal(el["value"][:, :, 0], expected)
            np.testing.assert_array_equal(el["time"][:], spec.times)
            np.testing.assert_array_equal(el["step"][:], np.arange(T))


def test_observables_match_the_formulas(run):
    path, spec, sol = run
    x, v, alpha = sol.positions, sol.velocities, spec.alpha
    c = np.maximum(x[:, :-1] - x[:, 1:], 0.0)
    expected = {
        "kinetic_energy": 0.5 * (v**2).sum(axis=1),
        "potential_energy": (c ** (alpha + 1)).sum(axis=1) / (alpha + 1),
        "momentum": v.sum(axis=1),
        "dissipated_energy": np.zeros(len(spec.times)),  # an elastic line
        "drive_work": np.zeros(len(spec.times)),  # a line without drives
    }
    compressions = x[:, :-1] - x[:, 1:]
    assert (compressions > 0).any() and (compressions < 0).any()
    assert expected["potential_energy"].min() > 0
    with h5py.File(path, "r") as f:
        assert sorted(f["observables"]) == sorted(expected)
        for name, want in expected.items():
            el = f["observables"][name]
            assert el["value"].shape == (len(spec.times),)
            np.testing.assert_allclose(el["value"][:], want, rtol=1e-13, atol=1e-15)
            np.testing.assert_array_equal(el["time"][:], spec.times)
            np.testing.assert_array_equal(el["step"][:], np.arange(len(spec.times)))


def test_results_events_diagnostics(run):
    path, _, sol = run
    with h5py.File(path, "r") as f:
        res = f["results"]
        for name in ("final_velocity", "final_position", "separation_velocity",
                     "separation_time"):
            assert res[name].shape == (sol.n,) and res[name].dtype == np.float64
            np.testing.assert_array_equal(res[name][:], getattr(sol, name))
        assert res.attrs["end_time"] == 12.5
        assert res.attrs["terminal"].dtype == np.bool_ and bool(res.attrs["terminal"])
        assert res.attrs["outcome"] == "terminal"
        assert res.attrs["message"] == sol.message

        ev = f["events"]
        assert ev["time"].dtype == np.float64
        assert ev["contact"].dtype == np.int64
        assert ev["kind"].dtype == np.int8
        np.testing.assert_array_equal(ev["time"][:], sol.event_time)
        # the solver counts contacts from 0; the file as it counts balls, from 1
        np.testing.assert_array_equal(ev["contact"][:], sol.event_contact + 1)
        assert ev["contact"].attrs["base"] == 1
        np.testing.assert_array_equal(ev["kind"][:], sol.event_kind)
        kinds = json.loads(ev["kind"].attrs["kinds"])
        assert kinds == {str(int(k)): k.name.lower() for k in EventKind}
        assert kinds["-1"] == "open" and kinds["1"] == "close"

        d = f["diagnostics"].attrs
        assert dict(d) == pytest.approx({
            "steps": 1234, "rejected_steps": 7, "events": 5, "momentum_error": 3e-16,
            "energy_error": -2e-15, "energy_correction": 4e-14, "wall_time": 0.25, "max_window": 5, "rtol": 1e-12,
            "velocity_floor": 1e-12, "closed_form_collisions": 0, "energy_floor": 0.0,
        })


def test_read_run_round_trip(run):
    path, spec, sol = run
    r = store.read_run(path)
    assert (r.n, r.k, r.alpha) == (6, 2, 1.5)
    assert r.format_version == 2 and r.creator_version == chainrun.__version__
    assert r.parameters["t_end"] is None and r.parameters["max_events"] is None
    assert r.parameters["overrides"] == {"chain.k": 2}
    np.testing.assert_array_equal(r.times, spec.times)
    np.testing.assert_array_equal(r.steps, np.arange(len(spec.times)))
    assert r.positions.shape == (len(spec.times), spec.n)
    np.testing.assert_array_equal(np.asarray(r.positions), sol.positions)
    np.testing.assert_array_equal(np.asarray(r.velocities), sol.velocities)
    np.testing.assert_array_equal(r.positions[2], sol.positions[2])
    np.testing.assert_array_equal(r.positions[-1], sol.positions[-1])
    np.testing.assert_array_equal(r.velocities[:, 3], sol.velocities[:, 3])
    np.testing.assert_array_equal(r.velocities[1:3, ::2], sol.velocities[1:3, ::2])
    np.testing.assert_array_equal(r.velocities[::-1, 0], sol.velocities[::-1, 0])
    for name in ("final_velocity", "final_position", "separation_velocity",
                 "separation_time", "event_time", "event_kind"):
        np.testing.assert_array_equal(getattr(r, name), getattr(sol, name))
    np.testing.assert_array_equal(r.event_contact, sol.event_contact + 1)
    assert r.outcome == Outcome.TERMINAL.value and Outcome(r.outcome) is Outcome.TERMINAL
    assert (r.end_time, r.terminal, r.message) == (12.5, True, sol.message)
    assert r.diagnostics["steps"] == 1234 and r.diagnostics["max_window"] == 5
    assert set(r.observables) == {"kinetic_energy", "potential_energy", "momentum",
                                  "dissipated_energy", "drive_work"}
    assert not np.any(r.observables["dissipated_energy"]) and r.dissipated_energy == 0.0
    assert not np.any(r.observables["drive_work"]) and r.drive_energy == 0.0
    np.testing.assert_array_equal(r.contact_dissipation, np.zeros(spec.n - 1))
    np.testing.assert_array_equal(r.wall_impulse, [0.0, 0.0])


def test_a_run_read_back_has_every_field_of_the_solution(run):
    # RunData holds the Solution it read: a field the solver gains is there without a
    # declaration of its own
    path, spec, sol = run
    r = store.read_run(path)
    assert isinstance(r.solution, Solution)
    for field in dataclasses.fields(Solution):
        getattr(r, field.name)
    assert set(dir(r)) >= {field.name for field in dataclasses.fields(Solution)}
    np.testing.assert_array_equal(r.solution.event_contact, sol.event_contact)
    assert r.solution.outcome is Outcome.TERMINAL and r.solution.diagnostics == sol.diagnostics
    np.testing.assert_array_equal(r.line.mass, spec.line.mass)
    with pytest.raises(AttributeError, match="no_such_field"):
        r.no_such_field


def test_every_item_is_in_the_schema_page(run):
    path, _, _ = run
    doc = SCHEMA.read_text()
    assert "chainrun-run" in doc and "chainrun-index" in doc
    names = set()
    with h5py.File(path, "r") as f:
        names |= set(f.attrs)

        def visit(name, obj):
            names.add(name.split("/")[-1])
            names.update(a for a in obj.attrs
                         if a not in ("CLASS", "NAME", "REFERENCE_LIST", "DIMENSION_LIST"))
        f.visititems(visit)
    missing = sorted(n for n in names if not re.search(rf"\b{re.escape(n)}\b", doc))
    assert not missing, f"not in docs/schema.md: {missing}"


# ------------------------------------------------------------------- netCDF / xarray


def test_xarray_sees_named_dimensions(run):
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    path, spec, sol = run
    with xr.open_datatree(path, engine="h5netcdf") as tree:
        pos = tree["particles/chain/position"]["value"]
        assert pos.dims == ("time", "ball", "spatial")
        assert tree["particles/chain/velocity"]["value"].dims == ("time", "ball", "spatial")
        assert tree["particles/chain/position"]["step"].dims == ("time",)
        np.testing.assert_array_equal(pos["ball"], np.arange(1, spec.n + 1))
        np.testing.assert_array_equal(pos["time"], spec.times)
        np.testing.assert_array_equal(pos.sel(ball=1, spatial="x"), sol.positions[:, 0])
        for name in ("kinetic_energy", "potential_energy", "momentum"):
            assert tree[f"observables/{name}"]["value"].dims == ("time",)
        for name in ("final_velocity", "final_position", "separation_velocity",
                     "separation_time"):
            assert tree["results"][name].dims == ("ball",)
        np.testing.assert_array_equal(tree["results"]["final_velocity"].sel(ball=spec.n),
                                      sol.final_velocity[-1])
        for name in ("time", "contact", "kind"):
            assert tree["events"][name].dims == ("event",)
        assert tree.attrs["format"] == "chainrun-run"
        assert tree["parameters"].attrs["n"] == spec.n
        assert tree["results"]["wall_impulse"].dims == ("wall",)
        assert list(tree["results"]["wall"].values) == ["left", "right"]
        named = {"time", "ball", "spatial", "event", "contact", "wall"}
        for node in tree.subtree:
            for var in node.ds.variables.values():
                assert set(var.dims) <= named, (node.path, var.dims)


def test_empty_run_has_valid_empty_groups(tmp_path):
    xr = pytest.importorskip("xarray")
    spec = make_spec(times=())
    sol = make_solution(spec, events=0, keep_snapshots=False)
    path = tmp_path / "empty.h5"
    with store.RunWriter(path, spec, velocity_floor=1e-12) as w:
        w.finish(sol)
    with h5py.File(path, "r") as f:
        assert f["particles/chain/position/value"].shape == (0, spec.n, 1)
        assert f["particles/chain/velocity/time"].shape == (0,)
        assert f["observables/momentum/value"].shape == (0,)
        assert f["events/time"].shape == (0,)
    r = store.read_run(path)
    assert r.times.shape == (0,) and r.positions.shape == (0, spec.n)
    assert np.asarray(r.positions).shape == (0, spec.n)
    assert r.event_kind.shape == (0,)
    with xr.open_datatree(path, engine="h5netcdf") as tree:
        assert tree["particles/chain/position"]["value"].dims == ("time", "ball", "spatial")
        assert tree["particles/chain/position"].sizes["time"] == 0


# ----------------------------------------------------------------- writing and storage


def test_snapshot_hook_copies_the_arrays_it_is_given(tmp_path):
    """The solver reuses its buffers: each snapshot must be taken at the call."""
    spec = make_spec(n=4, times=(0.0, 1.0, 2.0))
    sol = make_solution(spec, keep_snapshots=False)
    x, v = np.zeros(4), np.zeros(4)
    with store.RunWriter(tmp_path / "r.h5", spec, velocity_floor=1e-12) as w:
        for i, t in enumerate(spec.times):
            x[:] = i
            v[:] = 10 * i
            w.snapshot(i, t, x, v, observables(spec.line, t, x, v))
        x[:] = v[:] = -1
        w.finish(sol)
    r = store.read_run(tmp_path / "r.h5")
    np.testing.assert_array_equal(np.asarray(r.positions), np.repeat([[0.0], [1], [2]], 4, 1))
    np.testing.assert_array_equal(np.asarray(r.velocities)[:, 0], [0, 10, 20])


def test_energies_of_long_lines_match_the_formulas():
    # longer than physics' blocks, batched, and the last block a single contact
    from chainrun.solver import Line, physics

    n = 2 * physics._BLOCK + 2
    rng = np.random.default_rng(3)
    x = -np.cumsum(rng.normal(0.0, 0.1, (2, n)), axis=1)
    v = rng.normal(0.0, 0.5, (2, n))
    for alpha in (1.0, 1.5, 2.2):
        want = [math.fsum(max(a - b, 0.0) ** (alpha + 1) for a, b in zip(row[:-1], row[1:]))
                / (alpha + 1) for row in x]
        line = Line.make(n, alpha=alpha)
        np.testing.assert_allclose(physics.line_potential_energy(x, line), want, rtol=1e-12)
        assert physics.line_potential_energy(x[1], line) == pytest.approx(want[1], rel=1e-12)
    want = [0.5 * math.fsum(u * u for u in row) for row in v]
    np.testing.assert_allclose(physics.line_kinetic_energy(v, np.ones(n)), want, rtol=1e-12)


def test_large_arrays_are_chunked_and_compressed(tmp_path):
    # two chunks along the balls, the second one short: HDF5 itself decodes what the
    # writer compressed chunk by chunk, so any slip of the shuffle or the padding shows
    n = 2**16 + 100
    spec = make_spec(n=n, times=(0.0, 1.0))
    sol = make_solution(spec, events=5000, keep_snapshots=False)
    path = tmp_path / "big.h5"
    x = np.zeros(n)
    x[:3] = [2e-3, 1e-3, 0.0]
    xs = [x, x.copy()]
    xs[1][-1] = -0.0  # zero, but not the fill value's bytes: that chunk is stored
    v = np.random.default_rng(1).normal(size=(2, n))
    with store.RunWriter(path, spec, velocity_floor=1e-12) as w:
        for i, t in enumerate(spec.times):
            w.snapshot(i, t, xs[i], v[i], observables(spec.line, t, xs[i], v[i]))
        w.finish(sol)
    with h5py.File(path, "r") as f:
        for name in ("position", "velocity"):
            ds = f[f"particles/chain/{name}/value"]
            assert ds.chunks == (1, 2**16, 1)
            assert (ds.compression, ds.compression_opts, ds.shuffle) == ("gzip", 1, True)
            assert ds.maxshape == (None, n, 1)
        for name in ("results/final_velocity", "results/ball", "particles/chain/ball",
                     "events/time", "events/contact", "events/kind"):
            ds = f[name]
            assert ds.chunks is not None and ds.compression == "gzip", name
        assert f["events/time"].shape == (5000,)
        assert f["observables/potential_energy/value"][0] == pytest.approx(2 * 1e-3**2.5 / 2.5)
        position = f["particles/chain/position/value"]
        np.testing.assert_array_equal(position[:, :, 0], xs)
        assert np.signbit(position[1, -1, 0])
        # the one chunk that is all zero bytes is left to the fill value
        assert position.id.get_num_chunks() == 3
        np.testing.assert_array_equal(f["particles/chain/velocity/value"][:, :, 0], v)
        for name in ("final_velocity", "final_position", "separation_time"):
            np.testing.assert_array_equal(f[f"results/{name}"][:], getattr(sol, name))
        np.testing.assert_array_equal(f["results/ball"][:], np.arange(1, n + 1))
        np.testing.assert_array_equal(f["events/time"][:], sol.event_time)
        np.testing.assert_array_equal(f["events/contact"][:], sol.event_contact + 1)
        # the paper's line has one mass, one stiffness, ...: each is the fill value of
        # its dataset and stored nowhere, and reads back as that value
        for name, value in (("mass", 1.0), ("stiffness", 1.0), ("alpha", 1.5),
                            ("gap", 0.0), ("force", 0.0)):
            ds = f[f"model/{name}"]
            assert ds.id.get_num_chunks() == 0, name
            np.testing.assert_array_equal(ds[:], np.full(ds.shape, value))
        # the initial velocities are not one value: the chunk of the moving balls is
        # stored, the one of balls at rest is left to the fill value 0
        velocity = f["model/velocity"]
        assert velocity.id.get_num_chunks() == 1
        np.testing.assert_array_equal(velocity[:], np.r_[np.ones(2), np.zeros(n - 2)])
        np.testing.assert_array_equal(f["events/kind"][:], sol.event_kind)


def test_exception_in_writer_leaves_nothing(tmp_path):
    spec = make_spec()
    path = tmp_path / "k=2.h5"
    with pytest.raises(RuntimeError, match="solver blew up"):
        with store.RunWriter(path, spec, velocity_floor=1e-12) as w:
            assert w.temp_path.exists() and w.temp_path.parent == tmp_path
            assert w.temp_path.name == f".k=2.h5.partial-{os.getpid()}"
            w.snapshot(0, 0.0, np.zeros(spec.n), np.zeros(spec.n), AT_REST)
            raise RuntimeError("solver blew up")
    assert list(tmp_path.iterdir()) == []


def test_leaving_without_finish_leaves_nothing_and_keeps_an_old_file(tmp_path):
    spec = make_spec()
    path = tmp_path / "k=2.h5"
    path.write_bytes(b"old contents")
    with store.RunWriter(path, spec, velocity_floor=1e-12) as w:
        w.snapshot(0, 0.0, np.zeros(spec.n), np.zeros(spec.n), AT_REST)
    assert list(tmp_path.iterdir()) == [path] and path.read_bytes() == b"old contents"


def test_finish_replaces_an_existing_file_and_closes_the_writer(tmp_path):
    spec = make_spec()
    path = tmp_path / "k=2.h5"
    path.write_bytes(b"old contents")
    sol = make_solution(spec)
    with store.RunWriter(path, spec, velocity_floor=1e-12) as w:
        for i, t in enumerate(spec.times):
            x, v = sol.positions[i], sol.velocities[i]
            w.snapshot(i, t, x, v, observables(spec.line, t, x, v))
        w.finish(sol)
        with pytest.raises(StoreError, match="closed"):
            w.snapshot(9, 9.0, np.zeros(spec.n), np.zeros(spec.n), AT_REST)
    assert list(tmp_path.iterdir()) == [path]
    assert store.check_format(path) == 2


def test_bad_solution_in_finish_leaves_nothing(tmp_path):
    spec = make_spec()
    sol = make_solution(make_spec(n=7))
    with pytest.raises(StoreError, match="n = 7"):
        with store.RunWriter(tmp_path / "r.h5", spec, velocity_floor=1e-12) as w:
            w.finish(sol)
    assert list(tmp_path.iterdir()) == []


def test_snapshot_shape_is_checked(tmp_path):
    spec = make_spec()
    with store.RunWriter(tmp_path / "r.h5", spec, velocity_floor=1e-12) as w:
        with pytest.raises(ValueError, match="shape"):
            w.snapshot(0, 0.0, np.zeros(spec.n + 1), np.zeros(spec.n), AT_REST)
    assert list(tmp_path.iterdir()) == []


def test_write_run_needs_the_snapshots(tmp_path):
    spec = make_spec()
    with pytest.raises(StoreError, match="RunWriter"):
        write_run(tmp_path / "r.h5", spec, make_solution(spec, keep_snapshots=False),
                        velocity_floor=1e-12)
    assert list(tmp_path.iterdir()) == []


def test_unwritable_target_is_a_store_error(tmp_path):
    with pytest.raises(StoreError, match="cannot create run file") as info:
        store.RunWriter(tmp_path / "no" / "such" / "dir.h5", make_spec(), velocity_floor=1e-12)
    assert "\n" not in str(info.value)


# ----------------------------------------------------------------- format checking


def one_line_error(func, *args, match):
    with pytest.raises(StoreError, match=match) as info:
        func(*args)
    assert "\n" not in str(info.value)
    return str(info.value)


def test_check_format_accepts_path_and_open_file(run):
    path, _, _ = run
    assert store.check_format(path) == 2
    assert store.check_format(str(path), expected="chainrun-run") == 2
    with h5py.File(path, "r") as f:
        assert store.check_format(f) == 2


def test_check_format_rejects_foreign_hdf5(tmp_path):
    path = tmp_path / "foreign.h5"
    with h5py.File(path, "w") as f:
        f["data"] = np.arange(3)
    msg = one_line_error(store.check_format, path, match="not a chainrun run file")
    assert msg.startswith(str(path))
    with h5py.File(path, "a") as f:
        f.attrs["format"] = "foo"
    msg = one_line_error(store.read_run, path, match="not a chainrun run file")
    assert msg == f"{path}: not a chainrun run file (format 'foo')"


def test_check_format_rejects_truncated_and_non_hdf5(run, tmp_path):
    path, _, _ = run
    cut = tmp_path / "cut.h5"
    cut.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    assert one_line_error(store.check_format, cut, match="truncated") == \
        f"{cut}: truncated or not HDF5"
    one_line_error(store.read_run, cut, match="truncated or not HDF5")
    text = tmp_path / "notes.h5"
    text.write_text("not hdf5\n")
    one_line_error(store.check_format, text, match="truncated or not HDF5")
    one_line_error(store.read_run, tmp_path / "missing.h5", match="no such file")


def test_check_format_rejects_a_newer_version(run):
    path, _, _ = run
    with h5py.File(path, "a") as f:
        f.attrs["format_version"] = np.int64(3)
    msg = one_line_error(store.read_run, path, match="format version 3")
    assert msg == f"{path}: format version 3 is not supported (expected 1 or 2)"


def test_run_and_index_formats_are_not_confused(run, tmp_path):
    path, _, _ = run
    one_line_error(store.read_index, path, match="not a chainrun index file")
    index = tmp_path / "index.h5"
    store.write_index(index, "cradle", [])
    one_line_error(store.read_run, index, match=r"not a chainrun run file \(format 'chainrun-index'\)")


def test_damaged_run_file_is_a_store_error(run):
    path, _, _ = run
    with h5py.File(path, "a") as f:
        del f["results/final_velocity"]
    one_line_error(store.read_run, path, match="missing")


# ----------------------------------------------------------------------- index files


def index_entries(specs_and_files):
    return [
        dict(run_id=spec.run_id, file=file, n=spec.n, k=spec.k, alpha=spec.alpha,
             outcome="terminal", terminal=True, end_time=12.5, events=5, wall_time=0.25,
             config_hash=spec.config_hash)
        for spec, file in specs_and_files
    ]


def test_index_round_trip_and_links(tmp_path, monkeypatch):
    runs = tmp_path / "runs"
    runs.mkdir()
    done = []
    for k in (1, 2, 3):
        spec = make_spec(k=k)
        write_run(runs / f"k={k}.h5", spec, make_solution(spec, seed=k),
                        velocity_floor=1e-12)
        done.append((spec, f"k={k}.h5"))
    entries = index_entries(done)
    entries[2].update(outcome="stop_time", terminal=False, end_time=None)
    for e, extra in zip(entries, (0.5, 1, 2)):
        e["note"] = extra
    index = runs / "index.h5"
    store.write_index(index, "cradle", entries)
    assert sorted(p.name for p in runs.iterdir()) == ["index.h5", "k=1.h5", "k=2.h5", "k=3.h5"]
    assert store.check_format(index, expected="chainrun-index") == 1

    back = store.read_index(index)
    assert [e["run_id"] for e in back] == ["k=1", "k=2", "k=3"]
    assert back[0] == {**entries[0], "note": 0.5}
    assert back[2]["terminal"] is False and np.isnan(back[2]["end_time"])
    assert type(back[1]["n"]) is int and type(back[1]["alpha"]) is float
    assert back[1]["note"] == 1.0

    monkeypatch.chdir(tmp_path)  # links resolve against the index's folder, not the cwd
    with h5py.File(index, "r") as f:
        assert f.attrs["format"] == "chainrun-index" and f.attrs["format_version"] == 1
        assert f.attrs["experiment"] == "cradle"
        assert f["table/n"].dims[0][0].name == "/table/run"
        for e in entries:
            link = f["runs"].get(e["run_id"], getlink=True)
            assert isinstance(link, h5py.ExternalLink) and link.filename == e["file"]
            assert link.path == "/"
            linked = f["runs"][e["run_id"]]
            assert linked.attrs["format"] == "chainrun-run"
            assert linked["parameters"].attrs["k"] == int(e["run_id"][2:])
            assert linked["results/final_velocity"].shape == (6,)


def test_index_table_opens_with_xarray(tmp_path):
    xr = pytest.importorskip("xarray")
    spec = make_spec()
    index = tmp_path / "index.h5"
    store.write_index(index, "cradle", index_entries([(spec, "k=2.h5")]))
    with xr.open_dataset(index, group="table", engine="h5netcdf") as table:
        assert table["n"].dims == ("run",)
        assert table["run_id"].values.tolist() == ["k=2"]


def test_index_rejects_bad_entries_and_writes_nothing(tmp_path):
    spec = make_spec()
    index = tmp_path / "index.h5"
    good = index_entries([(spec, "a.h5")])
    one_line_error(store.write_index, index, "x", [{"run_id": "a"}], match="lack")
    one_line_error(store.write_index, index, "x", good + good, match="not unique")
    bad = [dict(good[0], run_id="a/b")]
    one_line_error(store.write_index, index, "x", bad, match="cannot name")
    assert list(tmp_path.iterdir()) == []


def test_empty_index(tmp_path):
    store.write_index(tmp_path / "index.h5", "nothing", [])
    assert store.read_index(tmp_path / "index.h5") == []


def test_large_arrays_are_compressed_only_where_it_pays(tmp_path):
    # a count and a ramp shrink to almost nothing; noise shrinks by a few per cent
    # under shuffle and deflate, which is not worth the time: stored as it is, and read
    # back the same either way
    import h5py

    from chainrun.store import _h5

    rng = np.random.default_rng(1)
    arrays = {"count": np.arange(10**5, dtype=np.int64),
              "ramp": np.linspace(0.0, 1.0, 10**5),
              "noise": rng.standard_normal(10**5)}
    with h5py.File(tmp_path / "a.h5", "w") as f:
        for name, data in arrays.items():
            _h5.array(f, name, data, [], name)
    with h5py.File(tmp_path / "a.h5") as f:
        assert {name: f[name].compression for name in arrays} == {
            "count": "gzip", "ramp": "gzip", "noise": None}
        for name, data in arrays.items():
            np.testing.assert_array_equal(f[name][()], data)
