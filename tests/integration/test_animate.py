"""``chainrun animate``: a GIF with a frame per snapshot, made without external programs;
MP4 without ffmpeg is refused in one line."""

from __future__ import annotations

import shutil

import pytest
from click.testing import CliRunner
from helpers import simulate_text
from PIL import Image

from chainrun.cli import main

CONFIG = """name = "movie"
[chain]
n = 8
k = 1
alpha = 1.0
[output]
times = {start = 0, stop = 12, step = 0.5}
"""


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    return simulate_text(tmp_path_factory.mktemp("animate"), CONFIG) / "run.h5"


def test_a_gif_has_a_frame_per_snapshot(run_file, tmp_path):
    out = tmp_path / "movie.gif"
    result = CliRunner().invoke(main, ["animate", str(run_file), "-o", str(out)])
    assert result.exit_code == 0, result.output
    with Image.open(out) as movie:
        assert movie.format == "GIF"
        assert movie.n_frames == 25  # t = 0, 0.5, ..., 12
        first = movie.convert("RGB").getcolors(1 << 20)
        movie.seek(24)
        last = movie.convert("RGB").getcolors(1 << 20)
    assert first != last  # the balls moved
    assert [p.name for p in tmp_path.iterdir()] == ["movie.gif"]  # no temporary left


def test_what_cannot_be_made_is_refused_in_one_line(run_file, tmp_path, monkeypatch):
    runner = CliRunner()
    cases = [(["-o", str(tmp_path / "m.avi")], "a movie is .gif or .mp4"),
             (["-o", str(tmp_path / "m.gif"), "--balls", "3:99"], "not within 1:8"),
             (["-o", str(tmp_path / "m.gif"), "--balls", "three"], "expected FIRST:LAST")]
    monkeypatch.setattr(shutil, "which", lambda name: None)
    cases.append((["-o", str(tmp_path / "m.mp4")], "MP4 needs the ffmpeg program"))
    for args, message in cases:
        result = runner.invoke(main, ["animate", str(run_file), *args])
        assert result.exit_code == 2, args
        assert message in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())
