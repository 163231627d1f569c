"""Atomic writes: a file appears whole or not at all, and a failed write leaves nothing."""

from __future__ import annotations

import pytest

from chainrun import atomic


def test_a_write_replaces_the_file_whole(tmp_path):
    path = tmp_path / "a.txt"
    path.write_text("old")
    seen = []

    def write_to(temp):
        temp.write_text("new")
        seen.append(path.read_text())  # the target is untouched while writing

    atomic.write(path, write_to)
    assert path.read_text() == "new" and seen == ["old"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt"]


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    path = tmp_path / "a.txt"
    path.write_text("old")

    def write_to(temp):
        temp.write_text("half")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError):
        atomic.write(path, write_to)
    assert path.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt"]


def test_leftovers_are_the_temporaries_of_any_process_for_those_names(tmp_path):
    for name in (".r1.h5.partial-123", ".r1.h5.partial-9", ".r2.h5.partial-5", "r1.h5",
                 ".r10.h5.partial-1"):
        (tmp_path / name).write_text("")
    found = [p.name for p in atomic.leftovers(tmp_path, ["r1.h5"])]
    assert found == [".r1.h5.partial-123", ".r1.h5.partial-9"]
    assert atomic.leftovers(tmp_path / "missing", ["r1.h5"]) == []
    assert atomic.temp_name(tmp_path / "r1.h5").name.startswith(".r1.h5.partial-")
