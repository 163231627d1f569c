"""``chainrun animate``: a GIF with a frame per snapshot, made without external programs;
balls drawn at their places plus their magnified displacements (checked against the
file read with h5py), walls, the magnification and the time with its unit on the
frame; what cannot be made is refused in one line."""

from __future__ import annotations

import re
import shutil

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from helpers import simulate_text
from matplotlib.text import Text
from PIL import Image

from chainrun.cli import main
from chainrun.plotting import style
from chainrun.plotting.animate import movie_figure
from chainrun.store import read_run

CONFIG = """name = "movie"
[chain]
n = 8
k = 1
alpha = 1.0
[walls.right]
stiffness = 1.0
[output]
times = {start = 0, stop = 12, step = 0.5}
"""

#: six 8 mm steel beads 2 µm apart, the last 1 µm from a steel wall, struck at 0.3 m/s
STEEL = """name = "beads"
units = "si"
[chain]
n = 6
k = 1
speed = 0.3
diameter = 0.008
material = "steel"
gap = 2.0e-6
[walls.right]
material = "steel"
gap = 1.0e-6
[output]
times = {start = 0.0, stop = 1.2e-4, step = 4.0e-6}
[solver]
t_end = 1.2e-4
"""


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    return simulate_text(tmp_path_factory.mktemp("animate"), CONFIG) / "run.h5"


@pytest.fixture(scope="module")
def steel_file(tmp_path_factory):
    return simulate_text(tmp_path_factory.mktemp("animate-si"), STEEL) / "run.h5"


def _movie(path, magnify=None):
    """The movie's figure, its artists by gid, and the balls' drawn centres and the time
    text at every frame."""
    run = read_run(path)
    frames = np.arange(run.times.size)
    with style():
        figure, draw = movie_figure(run, frames, 1, run.n, magnify=magnify)
    artists = {a.get_gid(): a for a in figure.findobj() if a.get_gid()}
    centres, clock = [], []
    for i in frames:
        balls, time = draw(i)
        centres.append(balls.get_offsets()[:, 0].copy())
        clock.append(time.get_text())
    return figure, artists, np.array(centres), clock


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


def test_a_movie_is_as_wide_as_asked_and_its_walls_show(tmp_path):
    """--width sets the frames' pixels (their height a third of it); a wall at the end
    of a long line is at least 1% of the line thick, not a sliver."""
    out = simulate_text(tmp_path, 'name = "w"\nunits = "si"\n[chain]\nn = 60\nk = 1\n'
                                  'speed = 0.1\ndiameter = 0.008\nmaterial = "steel"\n'
                                  '[walls.right]\n[output]\n'
                                  'times = {start = 0, stop = 1e-4, step = 5e-5}\n'
                                  '[solver]\nt_end = 1e-4\n') / "run.h5"
    movie = tmp_path / "w.gif"
    result = CliRunner().invoke(main, ["animate", str(out), "-o", str(movie), "--width",
                                       "1200"])
    assert result.exit_code == 0, result.output
    with Image.open(movie) as frames:
        assert frames.size == (1200, 360)
    run = read_run(out)
    with style():
        figure, _ = movie_figure(run, np.arange(run.times.size), 1, run.n)
    (wall,) = [a for a in figure.axes[0].patches if a.get_gid() == "wall/right"]
    assert wall.get_width() >= 0.01 * 60 * 8.0  # mm: 1% of 60 beads of 8 mm
    result = CliRunner().invoke(main, ["animate", str(out), "-o", str(movie), "--width", "50"])
    assert result.exit_code == 2 and "--width" in result.stderr


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="needs the ffmpeg program")
def test_an_mp4_is_made_by_ffmpeg(run_file, tmp_path):
    out = tmp_path / "movie.mp4"
    result = CliRunner().invoke(main, ["animate", str(run_file), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert out.read_bytes()[4:8] == b"ftyp"  # an ISO media file
    assert [p.name for p in tmp_path.iterdir()] == ["movie.mp4"]


def factor_of(stated: str) -> float:
    """The magnification a frame states (``displacements, magnified 2,000 times``)."""
    return float(re.search(r"magnified ([0-9,.]+) times", stated)[1].replace(",", ""))


def test_real_beads_are_drawn_to_scale_with_magnified_motion(steel_file):
    with h5py.File(steel_file) as h5:
        d = h5["model/diameter"][()]
        gap = h5["model/gap"][()]
        wall_gap = h5["model/walls/right"].attrs["gap"]
        x = h5["particles/chain/position/value"][:, :, 0]
        t = h5["particles/chain/position/time"][()]
    figure, artists, centres, clock = _movie(steel_file, magnify=1000)
    mm = 1e3
    rest = np.cumsum(d) - d / 2  # ball 1's left side at 0
    before = np.concatenate([[0.0], np.cumsum(gap)])
    assert np.allclose(centres, mm * (rest + 1000 * (before + x)), rtol=0, atol=1e-9)
    assert np.allclose(artists["balls"].get_widths(), mm * d)
    wall = artists["wall/right"]
    assert wall.get_x() == pytest.approx(mm * (d.sum() + 1000 * (gap.sum() + wall_gap)))
    assert "wall/left" not in artists
    assert artists["magnification"].get_text() == "displacements and gaps, magnified 1,000 times"
    # the time in microseconds, as the file has it
    for text, seconds in zip(clock, t):
        number, unit = re.fullmatch(r"t = ([0-9.]+) (µs)", text).groups()
        assert float(number) == pytest.approx(seconds * 1e6, abs=0.5)
    texts = [a.get_text() for a in figure.findobj(Text)]
    assert not [s for s in texts if "paper units" in s]
    axes = figure.axes[0]
    assert axes.get_xlabel() == "position along the line (mm)"
    assert "velocity (mm/s)" in texts  # the striker's 0.3 m/s is the largest speed
    title = figure.get_suptitle()
    assert title.startswith("beads") and "N = 6 steel spheres of 8 mm" in title
    left, right = axes.get_xlim()
    assert left < centres.min() - mm * d[0] / 2 and right > wall.get_x()


def test_the_automatic_magnification_shows_the_compression(steel_file):
    with h5py.File(steel_file) as h5:
        d = h5["model/diameter"][()]
        gap = h5["model/gap"][()]
        wall_gap = h5["model/walls/right"].attrs["gap"]
        x = h5["particles/chain/position/value"][:, :, 0]
    # largest compression of a contact or the wall; motion of the balls and the wall
    squeeze = max((x[:, :-1] - x[:, 1:] - gap).max(), (x[:, -1] - wall_gap).max())
    before = np.concatenate([[0.0], np.cumsum(gap)])
    motion = np.append((before + x).ravel(), gap.sum() + wall_gap)
    fits = [m * 10.0 ** p for p in range(-3, 8) for m in (1, 2, 5)
            if m * 10.0 ** p * squeeze <= 0.25 * d.min()
            and m * 10.0 ** p * np.ptp(motion) <= d.sum()]
    _, artists, centres, _ = _movie(steel_file)
    stated = artists["magnification"].get_text()
    factor = factor_of(stated)
    assert factor == pytest.approx(max(fits))
    # pressed balls overlap by the magnified compression, a visible share of a diameter
    overlap = ((d[:-1] + d[1:]) / 2 * 1e3 - np.diff(centres, axis=1)).max()
    assert overlap == pytest.approx(factor * (x[:, :-1] - x[:, 1:] - gap).max() * 1e3)
    assert 0.1 * d.min() * 1e3 < overlap <= 0.25 * d.min() * 1e3


def test_a_loaded_line_is_drawn_true_to_scale_and_its_motion_from_it_magnified(tmp_path):
    """Glass beads precompressed against a wall, struck: the static state is drawn true
    to scale (its squeeze, micrometres, does not show), the displacements from it
    magnified, by a factor that shows the compression beyond the static one."""
    path = simulate_text(tmp_path, """name = "loaded"
units = "si"
[chain]
n = 11
k = 1
speed = 0.05
diameter = 0.01
material = "glass"
precompression = 5.0
[walls.right]
material = "steel"
[output]
times = {start = 0.0, stop = 2.0e-4, step = 4.0e-6}
[solver]
t_end = 2.0e-4
""") / "run.h5"
    with h5py.File(path) as h5:
        d = h5["model/diameter"][()]
        x = h5["particles/chain/position/value"][:, :, 0]
        wall_gap = h5["model/walls/right"].attrs["gap"]
    figure, artists, centres, _ = _movie(path)
    factor = factor_of(artists["magnification"].get_text())
    mm = 1e3
    rest = np.cumsum(d) - d / 2
    np.testing.assert_allclose(centres, mm * (rest + x[0] + factor * (x - x[0])),
                               rtol=0, atol=1e-9)
    assert np.abs(x[0]).max() > 1e-7  # (a static squeeze of tenths of micrometres)
    right = mm * (d.sum() + min(wall_gap, 0.0) + factor * max(wall_gap, 0.0))
    assert artists["wall/right"].get_x() == pytest.approx(right)
    assert artists["magnification"].get_text().startswith(
        "displacements since t = 0, magnified ")
    squeeze = np.append(x[:, :-1] - x[:, 1:], x[:, -1:] - wall_gap, axis=1)
    beyond = (squeeze - np.maximum(squeeze[0], 0.0)).max()
    assert factor * beyond <= 0.25 * d.min() < 5 * factor * beyond  # (1, 2, 5 steps)


def test_a_line_in_paper_units_is_a_schematic(run_file):
    with h5py.File(run_file) as h5:
        x = h5["particles/chain/position/value"][:, :, 0]
        wall_gap = h5["model/walls/right"].attrs["gap"]
    figure, artists, centres, clock = _movie(run_file, magnify=0.5)
    assert np.allclose(centres, np.arange(1, 9) + 0.5 * x, rtol=0, atol=1e-12)
    assert artists["wall/right"].get_x() == pytest.approx(8.5 + 0.5 * wall_gap)
    assert artists["magnification"].get_text() == "displacements, scaled by 0.5"
    assert clock[1] == "t = 0.5 (paper units)"
    assert "schematic" in figure.axes[0].get_xlabel()


def test_what_cannot_be_made_is_refused_in_one_line(run_file, tmp_path, monkeypatch):
    runner = CliRunner()
    cases = [(["-o", str(tmp_path / "m.avi")], "a movie is .gif or .mp4"),
             (["-o", str(tmp_path / "m.gif"), "--balls", "3:99"], "not within 1:8"),
             (["-o", str(tmp_path / "m.gif"), "--balls", "5:2"], "the first is after the last"),
             (["-o", str(tmp_path / "m.gif"), "--balls", "three"], "expected FIRST:LAST"),
             (["-o", str(tmp_path / "m.gif"), "--magnify", "0"], "magnify 0.0: must be"),
             (["-o", str(tmp_path / "m.gif"), "--magnify", "nan"], "magnify nan: must be")]
    monkeypatch.setattr(shutil, "which", lambda name: None)
    cases.append((["-o", str(tmp_path / "m.mp4")], "MP4 needs the ffmpeg program"))
    for args, message in cases:
        result = runner.invoke(main, ["animate", str(run_file), *args])
        assert result.exit_code == 2, args
        assert message in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())
