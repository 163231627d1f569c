"""Reading bad files: truncated, foreign, other versions, damaged (chainrun.store).

``tests/unit/test_store.py`` covers one truncation (half the file), text, a missing file,
foreign HDF5 (no format; format "foo"), version 2, run and index files confused and a
missing dataset. This file adds truncation at many offsets, older versions and
versions that are not integers, formats that are not text, every group and attribute
of the schema missing, broken links, values that cannot be decoded, a folder, and
random damage: every case ends in a ``RunData`` or a one-line ``StoreError`` that
names the file.
"""

from __future__ import annotations

import random
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

from chainrun import runner, store
from chainrun.config import RunSpec
from chainrun.errors import StoreError
from chainrun.solver import Diagnostics, Outcome, Solution


def make_run(path: Path, n: int = 5, times=(0.0, 0.5, 1.0, 2.0)) -> Path:
    """A small run file written by hand (no solver)."""
    times = np.asarray(times, dtype=float)
    spec = RunSpec(experiment="x", run_id="run", n=n, k=1, alpha=1.5, times=times,
                   t_end=None, rtol=1e-12, max_events=None, overrides={},
                   config={"name": "x"}, config_hash="ab" * 32, source_text="name = 'x'\n")
    rng = np.random.default_rng(1)
    diag = Diagnostics(steps=10, rejected_steps=0, events=3, momentum_error=0.0,
                       energy_error=0.0, energy_correction=0.0, wall_time=0.01,
                       max_window=3, rtol=1e-12,
                       velocity_floor=1e-12)
    sol = Solution(
        n=n, k=1, alpha=1.5, outcome=Outcome.TERMINAL, message="terminal", end_time=3.0,
        terminal=True, final_position=rng.random(n), final_velocity=np.sort(rng.random(n)),
        separation_time=rng.random(n), separation_velocity=rng.random(n),
        event_time=np.array([0.5, 1.0, 2.0]), event_contact=np.array([0, 1, 0]),
        event_kind=np.array([-1, 1, -1], dtype=np.int8), times=times,
        positions=rng.random((len(times), n)), velocities=rng.random((len(times), n)),
        diagnostics=diag,
    )
    runner.write_run(path, spec, sol, velocity_floor=1e-12)
    return path


@pytest.fixture(scope="module")
def good(tmp_path_factory) -> Path:
    return make_run(tmp_path_factory.mktemp("good") / "run.h5")


def refused(path: Path, match: str | None = None, read=(store.check_format, store.read_run)):
    """Every reader in ``read`` raises a one-line StoreError naming ``path``."""
    messages = []
    for func in read:
        with pytest.raises(StoreError) as info:
            func(path)
        message = str(info.value)
        assert len(message.splitlines()) == 1, message
        assert message.startswith(f"{path}: "), message
        if match is not None:
            assert match in message, message
        messages.append(message)
    return messages


def copy_and(good: Path, tmp_path: Path, change) -> Path:
    path = tmp_path / "changed.h5"
    shutil.copy(good, path)
    with h5py.File(path, "a") as h5:
        change(h5)
    return path


# --- truncated ---------------------------------------------------------------------------


def test_truncated_at_many_offsets(good, tmp_path):
    raw = good.read_bytes()
    cuts = sorted({0, 1, 7, 8, 16, 47, 48, 96, 511, 512, 1024, 2048, len(raw) // 3,
                   len(raw) // 2, len(raw) - 4096, len(raw) - 512, len(raw) - 8, len(raw) - 1}
                  | set(range(0, len(raw), max(1, len(raw) // 40))))
    for cut in cuts:
        path = tmp_path / f"cut{cut}.h5"
        path.write_bytes(raw[:cut])
        refused(path, "truncated or not HDF5")
        assert store.run_config_hash(path) is None


def test_a_file_that_grew_is_still_read(good, tmp_path):
    """Bytes after the end (a copy that appended junk) do not stop a complete file."""
    path = tmp_path / "longer.h5"
    path.write_bytes(good.read_bytes() + b"\0" * 100)
    assert store.check_format(path) == store.RUN_FORMAT_VERSION


# --- not ours ----------------------------------------------------------------------------


@pytest.mark.parametrize("content", [b"", b"\x89HDF\r\n\x1a\n", b"\x89HDF\r\n\x1a\n" + b"\0" * 600,
                                     b"PK\x03\x04 a zip", "name = 'x'\n".encode()])
def test_not_hdf5(tmp_path, content):
    path = tmp_path / "x.h5"
    path.write_bytes(content)
    refused(path, "truncated or not HDF5")


def test_a_folder(tmp_path):
    folder = tmp_path / "run.h5"
    folder.mkdir()
    refused(folder, "is a folder")


def test_foreign_hdf5_files(tmp_path):
    path = tmp_path / "netcdf.h5"
    with h5py.File(path, "w") as h5:  # an HDF5 file of someone else, with a format of its own
        h5.attrs["format"] = "NETCDF4"
        h5["x"] = np.arange(3)
    assert refused(path)[1] == f"{path}: not a chainrun run file (format 'NETCDF4')"
    empty = tmp_path / "empty.h5"
    h5py.File(empty, "w").close()
    refused(empty, "not a chainrun run file (no format attribute)")


# --- format name and version -----------------------------------------------------------------


@pytest.mark.parametrize("value, message", [
    (np.bytes_(b"\xff\xfe"), "not a chainrun run file (format is not text)"),
    (np.int64(5), "not a chainrun run file (format '5')"),
    ("", "not a chainrun run file (format '')"),
    ("chainrun-run ", "not a chainrun run file (format 'chainrun-run ')"),
    ("CHAINRUN-RUN", "not a chainrun run file (format 'CHAINRUN-RUN')"),
    (np.array(["chainrun-run"], dtype=h5py.string_dtype()), "not a chainrun run file"),
])
def test_format_names(good, tmp_path, value, message):
    path = copy_and(good, tmp_path, lambda h5: h5.attrs.__setitem__("format", value))
    refused(path, message)


def test_format_name_as_bytes_is_accepted(good, tmp_path):
    path = copy_and(good, tmp_path,
                    lambda h5: h5.attrs.__setitem__("format", np.bytes_(b"chainrun-run")))
    assert store.read_run(path).n == 5


@pytest.mark.parametrize("version", [0, -1, 3, 99, np.uint64(2**64 - 1)])
def test_older_and_newer_versions(good, tmp_path, version):
    path = copy_and(good, tmp_path,
                    lambda h5: h5.attrs.__setitem__("format_version", version))
    refused(path, f"format version {int(version)} is not supported (expected 1 or 2)")


@pytest.mark.parametrize("version", ["1", 1.0, 1.5, np.inf, np.nan, np.array([1, 1]),
                                     np.bool_(True), b"1", None])
def test_versions_that_are_not_integers(good, tmp_path, version):
    def change(h5):
        if version is None:
            del h5.attrs["format_version"]
        else:
            h5.attrs["format_version"] = version

    path = copy_and(good, tmp_path, change)
    refused(path, "chainrun-run file without a valid format_version")


def test_index_version_is_checked_too(tmp_path):
    index = tmp_path / "index.h5"
    store.write_index(index, "x", [])
    with h5py.File(index, "a") as h5:
        h5.attrs["format_version"] = np.int64(0)
    refused(index, "format version 0 is not supported",
            read=[lambda p: store.check_format(p, expected=store.INDEX_FORMAT), store.read_index])


# --- the schema ------------------------------------------------------------------------------

GROUPS = ["parameters", "particles", "particles/chain", "particles/chain/position",
          "particles/chain/position/value", "particles/chain/position/time",
          "particles/chain/velocity", "particles/chain/velocity/value", "observables",
          "observables/kinetic_energy", "observables/potential_energy/value",
          "observables/momentum", "results", "results/final_velocity",
          "results/separation_time", "events", "events/time", "events/contact", "events/kind",
          "diagnostics", "h5md", "h5md/creator"]


@pytest.mark.parametrize("item", GROUPS)
def test_missing_groups_and_datasets(good, tmp_path, item):
    path = copy_and(good, tmp_path, lambda h5: h5.__delitem__(item))
    # the format is right, the content is not
    assert store.check_format(path) == store.RUN_FORMAT_VERSION
    (message,) = refused(path, "damaged run file (missing ", read=[store.read_run])
    assert item.split("/")[-1] in message


@pytest.mark.parametrize("where, name", [
    ("parameters", "n"), ("parameters", "k"), ("parameters", "alpha"), ("results", "outcome"),
    ("results", "message"), ("results", "end_time"), ("results", "terminal"),
    ("h5md/creator", "version"),
])
def test_missing_attributes(good, tmp_path, where, name):
    path = copy_and(good, tmp_path, lambda h5: h5[where].attrs.__delitem__(name))
    refused(path, f"damaged run file (missing /{where}@{name})", read=[store.read_run])


@pytest.mark.parametrize("where, name, value", [
    ("parameters", "config_resolved", "{not json"),
    ("parameters", "overrides", "[1, 2"),
    ("results", "end_time", "soon"),
    ("results", "outcome", np.bytes_(b"\xff")),
    ("results", "message", np.bytes_(b"\xc3")),
])
def test_values_that_cannot_be_read(good, tmp_path, where, name, value):
    path = copy_and(good, tmp_path, lambda h5: h5[where].attrs.__setitem__(name, value))
    refused(path, "damaged run file (", read=[store.read_run])


@pytest.mark.parametrize("link", [h5py.SoftLink("/nowhere"), h5py.ExternalLink("gone.h5", "/")])
@pytest.mark.parametrize("item", ["results", "results/final_velocity", "events/time"])
def test_broken_links(good, tmp_path, link, item):
    def change(h5):
        del h5[item]
        h5[item] = link

    path = copy_and(good, tmp_path, change)
    refused(path, "damaged run file (", read=[store.read_run])


def test_random_damage(good, tmp_path):
    """Bytes overwritten at random: read_run returns data or refuses in one line.

    (Damage inside the compressed snapshots is found only when they are read; see
    ``Snapshots``. Damage inside raw numbers cannot be found at all: HDF5 keeps
    checksums of its metadata, not of the data.)
    """
    raw = good.read_bytes()
    rng = random.Random(5)
    refusals = 0
    for trial in range(150):
        damaged = bytearray(raw)
        for _ in range(rng.randint(1, 4)):
            damaged[rng.randrange(len(damaged))] = rng.randrange(256)
        path = tmp_path / f"damaged{trial}.h5"
        path.write_bytes(bytes(damaged))
        try:
            store.read_run(path)
        except StoreError as exc:
            refusals += 1
            assert len(str(exc).splitlines()) == 1 and str(exc).startswith(f"{path}: ")
        assert store.run_config_hash(path) in (None, "ab" * 32)
    assert refusals > 0


def test_a_version_1_file_reads_as_version_2_numbers_it(good, tmp_path):
    """Version 1 numbered the event log's contacts from 0, kept the walls' impulses as
    attributes and wrote no dissipation on an elastic line: read, it numbers contacts
    from 1 like version 2 and gives zeros for what it did not write."""
    def older(h5):
        h5.attrs["format_version"] = np.int64(1)
        contact = h5["events/contact"]
        contact[...] = contact[()] - 1
        contact.attrs["base"] = np.int64(0)
        res = h5["results"]
        for name in ("wall_impulse", "wall_dissipation", "contact_dissipation"):
            del res[name]
        del res["wall"], res["contact"], h5["observables/dissipated_energy"]
        for name in ("dissipated_energy", "dissipated_energy_unit"):
            del res.attrs[name]
        res.attrs["right_wall_impulse"] = -0.25

    now = store.read_run(good)
    then = store.read_run(copy_and(good, tmp_path, older))
    assert then.format_version == 1
    np.testing.assert_array_equal(then.event_contact, now.event_contact)
    np.testing.assert_array_equal(then.event_contact, [1, 2, 1])  # as make_run logs them
    np.testing.assert_array_equal(then.wall_impulse, [0.0, -0.25])
    np.testing.assert_array_equal(then.contact_dissipation, np.zeros(4))
    np.testing.assert_array_equal(then.observables["dissipated_energy"], np.zeros(4))
