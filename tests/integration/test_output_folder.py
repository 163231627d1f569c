"""Output folders that cannot be written: a one-line error, a non-zero exit status, and
nothing under a final name.

The folders made unwritable here are temporary folders this test creates itself
(``chmod 500``). Permissions do not bind root: run as root, the operating system's
refusal is emulated by raising the same ``PermissionError`` it would raise.
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

import pytest
from click.testing import CliRunner

from chainrun.cli import main

CONFIG = """\
name = "out"
[chain]
n = 4
k = 1
alpha = 1.5
[output]
times = [0.0, 0.5]
[solver]
t_end = 1.0
"""


def simulate(tmp_path: Path, *args: str):
    config = tmp_path / "out.toml"
    config.write_text(CONFIG)
    result = CliRunner().invoke(main, ["simulate", str(config), *args])
    assert result.exception is None or isinstance(result.exception, SystemExit), \
        repr(result.exception)
    assert "Traceback" not in result.output
    return result


def errors(result) -> list[str]:
    return [line for line in result.stderr.splitlines() if line.startswith("chainrun: ")]


def everything(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


@pytest.fixture
def locked(tmp_path, monkeypatch):
    """A folder of ours with mode 500 (r-x): nothing can be created in it."""
    folder = tmp_path / "locked"
    folder.mkdir()
    folder.chmod(stat.S_IRUSR | stat.S_IXUSR)
    if os.access(folder, os.W_OK):  # root: emulate what the kernel would refuse
        real_mkdir, real_access = Path.mkdir, os.access

        def mkdir(self, *args, **kwargs):
            if folder in Path(self).absolute().parents:
                raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(self))
            return real_mkdir(self, *args, **kwargs)

        def access(path, mode, *args, **kwargs):
            if Path(path).absolute() == folder and mode & os.W_OK:
                return False
            return real_access(path, mode, *args, **kwargs)

        monkeypatch.setattr(Path, "mkdir", mkdir)
        monkeypatch.setattr(os, "access", access)
    yield folder
    folder.chmod(stat.S_IRWXU)


def test_a_folder_that_cannot_be_created(tmp_path, locked):
    result = simulate(tmp_path, "-o", str(locked / "out"))
    assert result.exit_code == 2
    assert errors(result) == [
        f"chainrun: error: cannot create output folder {locked / 'out'}: Permission denied"]
    assert everything(locked) == []


def test_a_folder_that_cannot_be_written(tmp_path, locked):
    result = simulate(tmp_path, "-o", str(locked))
    assert result.exit_code == 2
    assert errors(result) == [f"chainrun: error: output folder {locked} is not writable"]
    assert everything(locked) == []


def test_an_output_folder_that_is_a_file(tmp_path):
    target = tmp_path / "taken"
    target.write_text("mine")
    result = simulate(tmp_path, "-o", str(target))
    assert result.exit_code == 2
    assert "is a file" in result.stderr
    assert target.read_text() == "mine"


def test_an_output_folder_inside_a_file(tmp_path):
    target = tmp_path / "taken"
    target.write_text("mine")
    result = simulate(tmp_path, "-o", str(target / "out"))
    assert result.exit_code == 2
    assert errors(result) == [
        f"chainrun: error: cannot create output folder {target / 'out'}: Not a directory"]
    assert target.read_text() == "mine"


def test_a_run_file_name_taken_by_a_folder(tmp_path):
    out = tmp_path / "out"
    (out / "run.h5").mkdir(parents=True)
    (out / "run.h5" / "keep").write_text("mine")
    refused = simulate(tmp_path, "-o", str(out))
    assert refused.exit_code == 2 and "--force" in errors(refused)[0]
    assert everything(out) == ["run.h5", "run.h5/keep"]

    forced = simulate(tmp_path, "-o", str(out), "--force")
    assert forced.exit_code == 1
    (line,) = [line for line in errors(forced) if "failed" in line]
    assert line.startswith("chainrun: run run failed: ") and "run.h5" in line
    assert not [p for p in everything(out) if ".partial-" in p]
    assert (out / "run.h5" / "keep").read_text() == "mine"


def test_an_index_name_taken_by_a_folder(tmp_path):
    out = tmp_path / "out"
    (out / "index.h5").mkdir(parents=True)
    result = simulate(tmp_path, "-o", str(out))
    assert result.exit_code != 0
    assert len(errors(result)) >= 1 and "index.h5" in errors(result)[-1]
    assert not [p for p in everything(out) if ".partial-" in p]
