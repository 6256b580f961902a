"""`vibrofeed render`: the parts' real shapes, and pictures that show the scene.

The geometry (scene.py) is checked exactly on its arrays; the pictures are
rendered off-screen at a small size and checked on their pixels: not uniform,
the parts' colour present, and where the parts are along the track.
"""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

from helpers import parts, vibrofeed, write_bulk_result, write_result
from vibrofeed.errors import UsageError
from vibrofeed.pictures import scene
from vibrofeed.results.reader import Result

LENGTH, WIDTH, WALL = 0.02, 0.002, 0.001
SIZE = (320, 192)


def simple_track():
    """A floor (x in [0, LENGTH], |y| <= WIDTH/2) and two side walls, as triangles."""
    h = WIDTH / 2
    v = np.array([[0, -h, 0], [LENGTH, -h, 0], [LENGTH, h, 0], [0, h, 0],
                  [0, h, WALL], [LENGTH, h, WALL], [0, -h, WALL], [LENGTH, -h, WALL]], float)
    t = np.array([[0, 1, 2], [0, 2, 3], [3, 2, 5], [3, 5, 4], [1, 0, 6], [1, 6, 7]], np.int32)
    return v, t


def quat_about_x(angle):
    return np.array([np.cos(angle / 2), np.sin(angle / 2), 0.0, 0.0])


def bulk_file(path, xs, shape="sphere", speeds=None, n_frames=3, orientation=None, outlet=None):
    """Parts at x = xs on the track's centre line, resting on the floor, for n_frames frames
    (0.01 s apart: one period of the 100 Hz vibration); ``outlet``: the outlet table's attributes."""
    n = len(xs)
    r = 3e-4
    z = r if shape == "sphere" else 5e-5
    speeds = np.zeros(n) if speeds is None else np.asarray(speeds, float)
    frames = []
    for k in range(n_frames):
        pos = np.column_stack([np.asarray(xs, float) + 1e-4 * k, np.zeros(n), np.full(n, z)])
        p = parts(np.arange(1, n + 1), pos, radius=r,
                  velocity=np.column_stack([speeds, np.zeros(n), np.zeros(n)]))
        if orientation is not None:
            p["orientation"] = np.tile(orientation, (n, 1))
        frames.append((100 * k, 0.01 * k, p))
    code = {"sphere": "0", "chip": "1", "disc": "2"}[shape]
    variables = {"freq": ("100", "Hz", "vibration frequency", "100"),
                 "shape": (code, "", "part shape", "0"),
                 "part_size": ("6e-4", "m", "part size", "6e-4"),
                 "part_thickness": ("1e-4", "m", "thickness", "1e-4")}
    surface = [(np.array([2e-5 * k, 0, 1e-5 * k]), np.zeros(3)) for k in range(n_frames)]
    return write_bulk_result(path, frames, track=simple_track(), variables=variables, surface=surface,
                             outlet=outlet)


def red_mask(image):
    r, g, b = (image[..., i].astype(int) for i in range(3))
    return (r > 120) & (g < 60) & (b < 60)


# -- geometry -----------------------------------------------------------------------------
def test_shape_from_deck_variables():
    assert scene.part_shape({}) == scene.PartShape("sphere")
    chip = scene.part_shape({"shape": 1.0, "part_size": 3e-4, "part_thickness": 1e-4})
    assert (chip.kind, chip.size, chip.thickness, chip.axis) == ("chip", 3e-4, 1e-4, 2)
    assert scene.part_shape({"shape": "disc", "part_size": 3e-4, "part_thickness": 1e-4}).kind == "disc"
    # A template lying in the y = 0 plane puts the flat axis on y; sizes from its extent.
    template = np.array([[-1e-4, 0, -1e-4, 5e-5], [1e-4, 0, 1e-4, 5e-5]])
    s = scene.part_shape({"shape": 1.0}, template)
    assert s.axis == 1
    assert (s.size, s.thickness) == pytest.approx((3e-4, 1e-4), rel=1e-12, abs=0)  # m: rounding
    # a box keeps its own frame: L along x, W along y, T along z
    b = scene.part_shape({"shape": 3.0, "part_size": 1e-3, "part_width": 5e-4, "part_thickness": 3.5e-4})
    assert b.kind == "box" and b.extents().tolist() == [1e-3, 5e-4, 3.5e-4]
    points = scene.template_mesh(b)[0]
    assert (points.max(axis=0) - points.min(axis=0)).tolist() == pytest.approx([1e-3, 5e-4, 3.5e-4],
                                                                                 rel=1e-12, abs=0)


def test_rotation_matrices_are_rotations_and_nan_is_identity():
    q = np.random.default_rng(1).normal(size=(20, 4))
    rot = scene.rotation_matrices(q)
    # (dimensionless: equal up to rounding)
    assert np.allclose(rot @ rot.transpose(0, 2, 1), np.eye(3), rtol=0, atol=1e-12)
    assert np.allclose(np.linalg.det(rot), 1, rtol=0, atol=1e-12)
    assert np.allclose(scene.rotation_matrices([[np.nan] * 4, [0, 0, 0, 0]]), np.eye(3), rtol=0, atol=1e-12)
    # 90 degrees about x takes y to z
    assert np.allclose(scene.rotation_matrices(quat_about_x(np.pi / 2))[0] @ [0, 1, 0], [0, 0, 1],
                       rtol=0, atol=1e-12)


@pytest.mark.parametrize("maker, args, volume", [
    (scene.unit_sphere, (), 4 / 3 * np.pi), (scene.box, ((1, 2, 3),), 6.0),
    (scene.cylinder, (2.0, 0.5, 0), np.pi * 0.5), (scene.cylinder, (2.0, 0.5, 1), np.pi * 0.5),
    (scene.cylinder, (2.0, 0.5, 2), np.pi * 0.5)])
def test_template_shapes_are_whole_and_face_outwards(maker, args, volume):
    """The signed volume (divergence theorem) is the solid's: no face missing or turned in."""
    points, tris, normals = maker(*args)
    a, b, c = points[tris[:, 0]], points[tris[:, 1]], points[tris[:, 2]]
    assert np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6 == pytest.approx(volume, rel=0.05)
    # Normals: unit, outward (the shapes are convex around 0).
    assert np.allclose(np.linalg.norm(normals, axis=1), 1, rtol=0, atol=1e-12)
    assert (np.einsum("ij,ij->i", normals, points) > 0).all()


def test_sphere_is_closed():
    _, tris, _ = scene.unit_sphere()
    edges = {tuple(e) for e in np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])}
    assert len(edges) == 3 * len(tris) and all((b, a) in edges for a, b in edges)


def test_cylinder_axis_and_box_extents():
    points, _, _ = scene.cylinder(2.0, 0.5, axis=0)
    assert np.allclose(np.ptp(points, axis=0), [0.5, 2.0, 2.0], atol=0.02)
    points, _, _ = scene.box((1, 2, 3))
    assert np.allclose(np.ptp(points, axis=0), [1, 2, 3], rtol=0, atol=1e-12)


def test_shape_mesh_places_and_orients_chips(tmp_path):
    path = bulk_file(tmp_path / "chips.h5", [0.005, 0.01], shape="chip",
                     orientation=quat_about_x(np.pi / 2))
    with Result(path) as r:
        frame = scene.read_frame(r, -1)
        shape = scene.part_shape(r.parameters, r.body_template)
        mesh = scene.shape_mesh(frame, shape)
        assert len(mesh.points) == 2 * 24 and len(mesh.triangles) == 2 * 12
        for k in range(2):
            mine = mesh.points[mesh.owner == k]
            # Standing on an edge: the thickness now lies along y, the edge along z.
            assert np.allclose(np.ptp(mine, axis=0), [6e-4, 1e-4, 6e-4], rtol=0, atol=1e-15)  # m: rounding
            assert np.allclose(mine.mean(axis=0), frame.position[k], rtol=0, atol=1e-15)
            outward = np.einsum("ij,ij->i", mesh.normals[mesh.owner == k], mine - frame.position[k])
            assert (outward > 0).all()  # the normals turned with the chip
        normal, axis_x = scene.body_axes(frame, shape)
        assert np.allclose(normal, [0, -1, 0], rtol=0, atol=1e-12)  # unit vectors: rounding
        assert np.allclose(axis_x, [1, 0, 0], rtol=0, atol=1e-12)


def test_spheres_take_their_own_radius_and_track_moves_with_surface(tmp_path):
    path = bulk_file(tmp_path / "s.h5", [0.005])
    with Result(path) as r:
        frame = scene.read_frame(r, 2)
        mesh = scene.shape_mesh(frame, scene.PartShape())
        assert np.allclose(np.ptp(mesh.points, axis=0)[2], 6e-4, rtol=0, atol=1e-15)  # m: rounding
        vertices, triangles = scene.track_mesh(r, frame)
        assert np.allclose(vertices, simple_track()[0] + [4e-5, 0, 2e-5], rtol=0, atol=1e-15)
        with pytest.raises(UsageError, match="frame 3 out of range"):
            scene.read_frame(r, 3)


# -- pictures -----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def render():
    pytest.importorskip("pyvista")
    from vibrofeed.pictures.render import render_frame

    return render_frame


def test_picture_shows_the_parts_where_they_are(tmp_path, render):
    """Red parts near the inlet end appear on the left of the oblique view, near the outlet
    on the right; the picture is the size asked and not uniform."""
    images = {}
    for where, x in (("inlet", 0.002), ("outlet", 0.018)):
        with Result(bulk_file(tmp_path / f"{where}.h5", [x - 7e-4, x, x + 7e-4])) as r:
            images[where] = render(r, -1, size=SIZE, part_color="#ff0000")
    for where, image in images.items():
        assert image.shape == (SIZE[1], SIZE[0], 3)
        assert image.reshape(-1, 3).std(axis=0).min() > 10, "uniform picture"
        red = red_mask(image)
        assert red.sum() > 30, f"parts at the {where} not visible ({red.sum()} red pixels)"
    left = np.nonzero(red_mask(images["inlet"]))[1].mean()
    right = np.nonzero(red_mask(images["outlet"]))[1].mean()
    assert left < SIZE[0] / 2 < right


def test_speed_colours_span_the_scale(tmp_path, render):
    """One part at rest, one fast: both ends of viridis appear on the track (above the bar)."""
    with Result(bulk_file(tmp_path / "v.h5", [0.008, 0.012], speeds=[0.0, 0.05])) as r:
        image = render(r, -1, size=SIZE).astype(int)
    scene_part = image[: int(0.8 * SIZE[1])]  # the colour bar sits at the bottom
    r_, g, b = scene_part[..., 0], scene_part[..., 1], scene_part[..., 2]
    yellow = (r_ > 150) & (g > 150) & (b < 90)
    purple = (r_ < 110) & (g < 50) & (b > 50)
    assert yellow.sum() > 10 and purple.sum() > 10


def test_chips_lying_and_standing_differ(tmp_path, render):
    """The quaternion turns the boxes: a chip on its edge shows another outline than flat."""
    counts = []
    for angle in (0.0, np.pi / 2):
        path = bulk_file(tmp_path / f"c{angle:.1f}.h5", [0.006, 0.01, 0.014], shape="chip",
                         orientation=quat_about_x(angle))
        with Result(path) as r:
            counts.append(red_mask(render(r, -1, size=SIZE, part_color="#ff0000")).sum())
    assert min(counts) > 20 and abs(counts[0] - counts[1]) > 0.2 * max(counts)


def test_cluster_colouring(tmp_path, render):
    pytest.importorskip("scipy")
    from vibrofeed.pictures.render import SINGLE_COLOR, _cluster_sizes

    # Two touching spheres and one alone.
    with Result(bulk_file(tmp_path / "cl.h5", [0.006, 0.006 + 6e-4, 0.014])) as r:
        frame = scene.read_frame(r, 0)
        assert list(_cluster_sizes(r, frame)) == [2, 2, 1]
        image = render(r, 0, color="cluster", size=SIZE)[: int(0.8 * SIZE[1])].astype(int)
    grey = int(SINGLE_COLOR[1:3], 16)
    # The single part is grey (shaded), the pair coloured from the size scale (plasma).
    coloured = (np.abs(image[..., 0] - image[..., 1]) > 60) | (np.abs(image[..., 1] - image[..., 2]) > 60)
    assert coloured.sum() > 10
    assert (np.abs(image - grey) < 40).all(axis=-1).sum() > 10


def test_result_without_track_gets_a_floor(tmp_path, render):
    path = write_result(tmp_path / "single.h5",
                        [(0, 0.0, parts([1], [[0, 0, 5e-4]])), (1, 0.01, parts([1], [[1e-3, 0, 5e-4]]))])
    with Result(path) as r:
        image = render(r, -1, size=SIZE, part_color="#ff0000")
    assert red_mask(image).sum() > 30


def _ffmpeg():
    return shutil.which("ffmpeg")


@pytest.mark.skipif(_ffmpeg() is None, reason="MP4 needs ffmpeg (apt-get install ffmpeg)")
def test_movie_has_every_frame(tmp_path, render):
    from vibrofeed.pictures.render import render as render_file

    out = tmp_path / "m.mp4"
    with Result(bulk_file(tmp_path / "m.h5", [0.005, 0.01, 0.015], n_frames=4)) as r:
        done = render_file(r, out, size=(160, 96), fps=10)
    assert done.frames == 4 and done.size == (160, 96)
    assert "stroboscopic" in done.note and "output_dt=0.00125" in done.note   # one period apart
    raw = subprocess.run([_ffmpeg(), "-loglevel", "error", "-i", str(out), "-f", "rawvideo",
                          "-pix_fmt", "rgb24", "-"], capture_output=True, check=True).stdout
    video = np.frombuffer(raw, np.uint8).reshape(-1, 96, 160, 3)
    assert len(video) == 4 and video[0].std() > 10


def test_a_png_is_written_whole_or_not_at_all(tmp_path, render):
    """VTK encodes into memory, Python writes the file (a full disk: an OSError, no libpng
    noise); a failed write keeps an older file and leaves no temporary one."""
    from vibrofeed.pictures.render import render as render_file
    from vibrofeed.pictures.render import write_whole

    out = tmp_path / "p.png"
    with Result(bulk_file(tmp_path / "p.h5", [0.005, 0.01])) as r:
        render_file(r, out, size=(160, 96))
    data = out.read_bytes()
    assert data.startswith(b"\x89PNG\r\n\x1a\n") and data[-8:-4] == b"IEND"
    with pytest.raises(TypeError):  # a write that fails half-way
        write_whole(out, "not bytes")
    assert out.read_bytes() == data and sorted(p.name for p in tmp_path.iterdir()) == ["p.h5", "p.png"]


def test_ffmpeg_failing_is_named_by_its_first_error_line(tmp_path, monkeypatch, render):
    """ffmpeg names the cause first and its consequences after: the last line ("Error
    initializing output stream 0:0 --") says nothing."""
    from vibrofeed.errors import OutputError
    from vibrofeed.pictures.render import ffmpeg_error
    from vibrofeed.pictures.render import render as render_file

    stderr = ("Could not write header for output file #0 (incorrect codec parameters ?): "
              "No space left on device\nError initializing output stream 0:0 -- \n")
    assert ffmpeg_error(stderr) == "Could not write header for output file #0: No space left on device"
    assert ffmpeg_error("\n[libx264 @ 0x1] broken   pipe\nConversion failed!\n") == \
        "[libx264 @ 0x1] broken pipe"
    assert ffmpeg_error("") == "?"
    fake = tmp_path / "bin" / "ffmpeg"  # an ffmpeg that fails as on a full disk
    fake.parent.mkdir()
    fake.write_text("#!/bin/sh\ncat > /dev/null\nprintf '%s' \"$FFMPEG_ERR\" >&2\nexit 1\n")
    fake.chmod(0o755)
    monkeypatch.setenv("PATH", f"{fake.parent}:/usr/bin:/bin")
    monkeypatch.setenv("FFMPEG_ERR", stderr)
    out = tmp_path / "m.mp4"
    with Result(bulk_file(tmp_path / "m.h5", [0.005, 0.01], n_frames=2)) as r:
        with pytest.raises(OutputError, match=f"^ffmpeg could not write {out}: Could not write header "
                                              "for output file #0: No space left on device$"):
            render_file(r, out, size=(160, 96))


def test_command_line(tmp_path, capsys):
    from vibrofeed.cli import main

    path = bulk_file(tmp_path / "run.h5", [0.005, 0.01])
    out = tmp_path / "pic.png"
    proc = vibrofeed("render", path, "-o", out, "--size", "240x160", "--frame", "1",
                     "--color", "cluster", check=True)
    assert "wrote" in proc.stdout and out.stat().st_size > 1000
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    capsys.readouterr()
    for args, fragment in ((["-o", str(tmp_path / "x.gif")], "must end in .png"),
                           (["--frame", "7"], "frame 7 out of range"),
                           (["--size", "big"], "WIDTHxHEIGHT")):
        try:
            code = main(["render", str(path), *args])
        except SystemExit as exc:  # argparse's own usage errors
            code = exc.code
        err = capsys.readouterr().err
        assert code == 2 and fragment in err and err.count("\n") == 1, err


# -- what a picture says: speed scale, length scale, run, vibration phase -------------------
@pytest.fixture
def painter():
    """A painter over frames of a result, closed afterwards."""
    pytest.importorskip("pyvista")
    from vibrofeed.pictures.render import _Painter

    made = []

    def make(result, frames, color="speed", size=SIZE):
        made.append(_Painter(result, color, size, np.asarray(frames), None))
        return made[-1]

    yield make
    for p in made:
        p.close()


def test_speed_scale_spans_the_parts_on_the_track_and_counts_the_others(tmp_path, painter):
    """Three parts on the track (x <= the outlet edge at LENGTH), two past the edge ten times
    faster: the scale's top is the fastest part on the track, the bar counts the two."""
    xs = [0.004, 0.01, 0.016, LENGTH + 5e-4, LENGTH + 1e-3]
    speeds = [0.010, 0.025, 0.018, 0.25, 0.3]
    outlet = {"outlet_x": LENGTH, "catch_z": -3e-4, "method": "synthetic"}
    with Result(bulk_file(tmp_path / "clip.h5", xs, speeds=speeds, outlet=outlet)) as r:
        p = painter(r, [2])
        frame = scene.read_frame(r, 2)
        p.draw(frame)
        # independently: on the track is x - surface x <= the outlet edge (the surface moved 4e-5)
        x_track = frame.position[:, 0] - frame.surface_position[0]
        expected = frame.speed[x_track <= LENGTH].max()
        assert expected == pytest.approx(0.025, rel=1e-9)
        low, high = p.plotter.actors["parts"].mapper.scalar_range
        assert (low, high) == pytest.approx((0.0, expected * 1e3), rel=1e-9)   # mm/s
        titles = list(p.plotter.scalar_bars.keys())
        assert len(titles) == 1 and "speed [mm/s]" in titles[0]
        assert "clipped: 2 parts" in titles[0] and titles[0].endswith("off the track:")


def test_no_clipping_note_when_every_part_is_on_the_scale(tmp_path, painter):
    with Result(bulk_file(tmp_path / "slow.h5", [0.005, 0.01], speeds=[0.01, 0.02])) as r:
        p = painter(r, [0])
        p.draw(scene.read_frame(r, 0))
        assert list(p.plotter.scalar_bars.keys()) == ["speed [mm/s]"]


def dark_columns(rows):
    """Columns of an (H, W, 3) strip holding any clearly non-white pixel."""
    return np.nonzero((rows.astype(int).sum(axis=-1) < 600).any(axis=0))[0]


def test_scale_bar_has_the_length_it_says(tmp_path, render):
    """Lengths along the track are true to scale: the bar's pixels over its length in mm equal
    the track's pixels (measured on the picture) over the track's LENGTH."""
    from vibrofeed.pictures.render import BAR_Y_PX, _Painter

    w, h = 640, 360
    with Result(bulk_file(tmp_path / "bar.h5", [0.01])) as r:
        p = _Painter(r, "speed", (w, h), np.array([2]), "#ff0000")
        try:
            p.draw(scene.read_frame(r, 2))
            image = p.image()
            length, _ = p.scale_bar()
        finally:
            p.close()
    scene_rows = image[int(0.3 * h):int(0.7 * h), : int(0.85 * w)]   # the track, no text
    cols = dark_columns(scene_rows)
    track_px = cols.max() - cols.min() + 1
    bar_row = image[h - BAR_Y_PX - 2]
    black = np.nonzero(bar_row.astype(int).sum(axis=-1) < 60)[0]
    bar_px = black.max() - black.min() + 1
    assert len(black) == bar_px   # one solid bar
    assert bar_px == pytest.approx(length / LENGTH * track_px, abs=2)   # a pixel at each end
    assert length in (1e-3, 2e-3, 5e-3, 1e-2)


def test_picture_names_the_run_and_the_vibration_phase(tmp_path, painter):
    with Result(bulk_file(tmp_path / "named.h5", [0.01])) as r:
        p = painter(r, [1])
        p.draw(scene.read_frame(r, 1))
        footer = p.plotter.actors["footer"].GetInput()
        title = p.plotter.actors["title"].GetText(2)   # the upper-left corner
    assert footer.startswith("named.h5; deck synthetic_bulk; freq 100 Hz") and "shape sphere" in footer
    assert "part_size 0.6 mm" in footer   # micro-scale lengths in mm
    assert "t = 0.0100 s" in title and "phase 0.00 T" in title
    assert "stroboscopic" not in title   # one picture: no movie to alias


def test_stroboscopic_sampling_is_detected_and_said():
    from vibrofeed.pictures.render import nice_length, stroboscopic

    t = np.arange(5) * 0.01
    assert stroboscopic(t, 100.0) == 1
    assert stroboscopic(t[::2], 100.0) == 2
    assert stroboscopic(t, 70.0) == 0          # 0.7 periods apart: the phase drifts
    assert stroboscopic(t, 0.0) == 0
    assert stroboscopic(t[:1], 100.0) == 0
    assert [nice_length(x) for x in (0.0042, 0.0019, 0.01, 7e-4)] == pytest.approx(
        [2e-3, 1e-3, 1e-2, 5e-4], rel=1e-12)


def test_movie_frames_say_they_are_stroboscopic(tmp_path, painter):
    with Result(bulk_file(tmp_path / "strobe.h5", [0.01], n_frames=4)) as r:
        p = painter(r, np.arange(4))
        p.draw(scene.read_frame(r, 3))
        title = p.plotter.actors["title"].GetText(2)   # the upper-left corner
    assert "stroboscopic: one frame every 1 vibration period" in title


@pytest.mark.skipif(_ffmpeg() is None, reason="MP4 needs ffmpeg (pip install imageio-ffmpeg)")
def test_command_line_says_a_movie_is_stroboscopic(tmp_path):
    path = bulk_file(tmp_path / "run.h5", [0.005, 0.01], n_frames=3)
    out = tmp_path / "m.mp4"
    proc = vibrofeed("render", path, "-o", out, "--size", "160x96", "-q", check=True)
    assert f"wrote {out}" in proc.stdout and out.stat().st_size > 0
    assert proc.stderr.startswith("note: the frames drawn fall every 1 vibration period")
