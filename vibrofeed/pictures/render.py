"""Draw a result off-screen with pyvista: a PNG of one frame, an MP4 of many.

The track is drawn at the frame's surface position (a feeder line's sections each at
its own recorded position), the parts with their real
shapes (:mod:`.scene`), coloured by speed, by the size of the cluster of
touching parts they belong to (single parts grey) or by their orientation state
(:data:`STATE_COLORS`: correctly oriented parts in one colour, the others in their
state's), seen from the front and
above in parallel projection: lengths along the track are true to scale on the
screen, and a scale bar in mm says how long. The speed scale spans the parts on
the track: the few parts falling past the outlet edge, ten times faster, would
otherwise give every conveyed part one colour; they take the colour above the
scale, and the bar says how many they are. The title holds the time,
the frame and the vibration phase; the footer names the run
(:func:`.caption.run_caption`). A movie whose frames fall a whole number of
vibration periods apart samples the vibration stroboscopically: every frame
says so (the track's oscillation is not seen, the parts' drift is).

No display is needed: without ``DISPLAY`` VTK is asked for its EGL window
(Mesa's software renderer, Debian packages ``libegl1`` and
``libgl1-mesa-dri``), which renders to memory. Movies are encoded by the
ffmpeg on the PATH (Debian package ``ffmpeg``).
"""

from __future__ import annotations

import os
import re
import secrets
import shutil
import time as _time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import OutputError, UsageError, said
from .caption import run_caption
from .scene import FrameData, floor_patch, part_shape, read_frame, section_motion, shape_mesh, track_mesh

COLORINGS = ("speed", "cluster", "state")
DEFAULT_SIZE = (1280, 720)   # multiples of 16: what H.264 encoders want
TRACK_COLOR = "#9aa3ad"
# The track is seen through: its walls stand in front of the parts riding against them.
TRACK_OPACITY = 0.45
SINGLE_COLOR = "#d0d0d0"     # parts not touching any other (cluster of one)
BACKGROUND = "white"
# --color state (vibrofeed.orientation): Okabe-Ito colours, told apart with any colour vision.
# The correctly oriented parts (whatever their state) take bluish green; the others their
# state's colour: "up" there means marked face up but not correct (crosswise, wrong end).
CORRECT_COLOR = "#009e73"    # bluish green
STATE_COLORS = {"up": "#0072b2",     # blue
                "down": "#d55e00",   # vermillion
                "side": "#f0e442",   # yellow
                "end": "#cc79a7"}    # reddish purple
NO_STATE = "spheres have no orientation state: use --color speed or cluster"
# Parts closer than this fraction of the mean part diameter count as touching for
# --color cluster: the default of the singulation analysis (postproc/singulation.py),
# so that the picture shows the clusters it counts.
TOUCH_DIAMETERS = 0.01
# Direction from the track's centre to the camera: in front (-y) and above (+z), square
# to the track (no x): in parallel projection x then maps to the screen's x at one scale.
VIEW_DIRECTION = np.array([0.0, -0.8, 1.0])
# Frames this close (in periods) to a whole number of vibration periods apart are stroboscopic.
STROBE_TOLERANCE = 0.02
# Fraction of the picture's width left to the scene (the colour bar takes the rest).
SCENE_WIDTH = 0.86
MARGIN_PX = 12
# Room in view past the far end of the track, as a fraction of its length: parts falling off.
FALL_ROOM = 0.12
BAR_Y_PX = 30  # the scale bar's height above the picture's bottom edge (the footer below it)


@dataclass(frozen=True)
class Rendered:
    """What :func:`render` wrote: the file, the frames drawn, the picture size, the seconds spent."""

    path: Path
    frames: int
    size: tuple[int, int]
    seconds: float
    note: str = ""  # what the viewer should know (a stroboscopic movie)


def _offscreen_pyvista():
    """pyvista set up for drawing without a display."""
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        from ctypes.util import find_library

        # VTK would first try X and warn that there is no server; EGL needs none. Without
        # libEGL, VTK's own fallback (OSMesa, if installed) is left to choose.
        if find_library("EGL"):
            os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista as pv

    pv.OFF_SCREEN = True
    return pv


def _polydata(pv, points: np.ndarray, triangles: np.ndarray):
    faces = np.column_stack([np.full(len(triangles), 3), triangles]).ravel()
    return pv.PolyData(np.asarray(points, dtype=float), faces=faces)


def _cluster_sizes(result, frame: FrameData) -> np.ndarray:
    """(N,) the number of parts in the cluster of touching parts each part belongs to
    (clumps touch when any of their spheres touch, as the singulation analysis counts)."""
    from ..postproc.clusters import clump_labels, cluster_labels

    if len(frame) == 0:
        return np.zeros(0)
    tolerance = TOUCH_DIAMETERS * 2 * float(np.mean(frame.radius))
    if result.body_template is not None:
        labels = clump_labels(frame.position, frame.orientation, result.body_template, tolerance)
    else:
        labels = cluster_labels(frame.position, frame.radius, tolerance)
    return np.bincount(labels)[labels].astype(float)


def on_track(result, position: np.ndarray, surface_position: np.ndarray) -> np.ndarray:
    """(..., N) True for parts over the track: not past its outlet edge along x in the
    track's frame (every part when the run has no outlet edge). ``surface_position`` is the
    displacement of the section that ends at the outlet edge (a line's last)."""
    from ..postproc.feedrate import outlet_x

    edge = outlet_x(result)
    x = position[..., 0] - np.asarray(surface_position)[..., 0, None]
    inside = np.isfinite(x)
    return inside & (x <= edge) if np.isfinite(edge) else inside


def speed_limit(result, frames: np.ndarray) -> float:
    """Top of the speed colour scale [m/s]: the largest speed of a part on the track over
    ``frames`` (fixed over a movie, so that colours compare between frames). Parts falling
    past the outlet are left out: ten times faster than the conveyed ones, they would give
    every conveyed part one colour."""
    top = 0.0
    for k in range(0, len(frames), 256):
        block = frames[k:k + 256]
        speed = np.linalg.norm(result.read("velocity", frames=block), axis=-1)
        # the outlet edge moves with the last section (a feeder line's section 2)
        track = on_track(result, result.read("position", frames=block),
                         section_motion(result, block)[0][-1])
        for row, keep in zip(speed, track):
            row = row[keep & np.isfinite(row)]
            if len(row):
                top = max(top, float(row.max()))
    return top if top > 0 else 1e-3


def nice_length(span: float) -> float:
    """The largest 1, 2 or 5 x 10^k not above ``span`` (> 0): a scale bar's length."""
    k = np.floor(np.log10(span))
    for m in (5.0, 2.0, 1.0):
        if m * 10 ** k <= span:
            return float(m * 10 ** k)
    return float(10 ** k)


def stroboscopic(times: np.ndarray, freq: float) -> int:
    """Periods between successive frames when they fall a whole number (>= 1) of vibration
    periods apart (within ``STROBE_TOLERANCE``), else 0."""
    if len(times) < 2 or not freq > 0:
        return 0
    cycles = np.diff(np.asarray(times, dtype=float)) * freq
    whole = np.round(cycles)
    if (whole >= 1).all() and (np.abs(cycles - whole) <= STROBE_TOLERANCE).all() and len(set(whole)) == 1:
        return int(whole[0])
    return 0


def _view_bounds(result, frames: np.ndarray) -> np.ndarray:
    """(xmin, xmax, ymin, ymax, zmin, zmax) the camera frames: the track at rest, or without
    a track the parts' range over the frames drawn."""
    mesh = result.track_mesh
    if mesh is not None:
        v = np.asarray(mesh[0], dtype=float)
        lo, hi = v.min(axis=0), v.max(axis=0)
    else:
        lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
        for k in range(0, len(frames), 256):
            p = result.read("position", frames=frames[k:k + 256]).reshape(-1, 3)
            p = p[np.isfinite(p).all(axis=1)]
            if len(p):
                lo, hi = np.minimum(lo, p.min(axis=0)), np.maximum(hi, p.max(axis=0))
        if not np.isfinite(lo).all():
            lo, hi = np.full(3, -1e-3), np.full(3, 1e-3)
        pad = 0.1 * max(float((hi - lo).max()), 1e-3)
        lo, hi = lo - pad, hi + pad
    return np.column_stack([lo, hi]).ravel()


class PartStates:
    """Each part's orientation state at a frame, read as the orientation analysis reads it
    (:mod:`vibrofeed.postproc.orientation`: the body frame from the result's template, the
    path's direction where the part is: +x along a line, up a bowl's helix)."""

    def __init__(self, result, correct=None):
        from ..orientation import Correct, parse_correct
        from ..postproc.path import feeder_of

        if result.body_template is None:
            raise UsageError(NO_STATE)
        if correct is None:  # the run's own (its parameter correct), else the default
            run = result.parameters.get("correct")
            correct = parse_correct(str(run), "correct") if run else Correct()
        self.correct = correct if isinstance(correct, Correct) else parse_correct(correct, "--correct")
        self.result, self.feeder = result, feeder_of(result.parameters)

    def of(self, frame: FrameData):
        """(:class:`vibrofeed.orientation.States`, (N,) correct) of the parts of ``frame``."""
        from ..orientation import part_states
        from ..postproc.orientation import path_directions
        from ..postproc.path import along

        s = along(self.result, np.array([frame.index]), 0, frame.position[None])[0][0]
        tangent, up = path_directions(self.feeder, s)
        states = part_states(frame.orientation, self.result.body_template, tangent, up)
        return states, self.correct.of(states)

    def categories(self, frame: FrameData) -> np.ndarray:
        """(N,) each part's colour in :func:`state_palette`: 0 correct, else 1 + its state."""
        states, correct = self.of(frame)
        return np.where(correct, 0, 1 + states.state).astype(float)


def most_correct_frame(result, frames, correct=None) -> int | None:
    """Of the frame indices ``frames``, the last at which the most parts are correctly oriented
    (:class:`PartStates`; ``correct`` as there), None when none has one: a picture of a line
    with the parts it delivers in it, not only the rejects in the making (``vibrofeed demo``)."""
    states = PartStates(result, correct)
    pick, most = None, 0
    for i in frames:
        n = int(np.count_nonzero(states.of(read_frame(result, int(i)))[1]))
        if n and n >= most:
            pick, most = int(i), n
    return pick


def _swatch(pv, color: str):
    """A unit square coloured ``color`` by its cell's RGB: a legend entry's symbol."""
    square = pv.PolyData(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float),
                         faces=[4, 0, 1, 2, 3])
    rgb = [int(color[k:k + 2], 16) for k in (1, 3, 5)]
    square.cell_data["rgb"] = np.array([rgb], dtype=np.uint8)
    return square


def state_palette() -> list[tuple[str, str]]:
    """(label, colour) of --color state's categories, in their order (PartStates.categories)."""
    return [("correct", CORRECT_COLOR), *STATE_COLORS.items()]


class _Painter:
    """One off-screen plotter drawing frame after frame of one result."""

    def __init__(self, result, color: str, size, frames: np.ndarray, part_color=None, correct=None):
        if color not in COLORINGS:
            raise UsageError(f"--color must be one of {', '.join(COLORINGS)}, got {said(color)}")
        # (before the plotter: spheres are refused without opening a window)
        self.states = PartStates(result, correct) if color == "state" and part_color is None else None
        self.pv = pv = _offscreen_pyvista()
        self.result, self.color, self.part_color = result, color, part_color
        self.shape = part_shape(result.parameters, result.body_template)
        self.bounds = _view_bounds(result, frames)
        # A movie keeps one colour scale over its frames, so that colours compare.
        movie = len(frames) > 1
        self.speed_top = speed_limit(result, frames) if color == "speed" else None
        self.cluster_top = (max(_cluster_sizes(result, read_frame(result, int(k))).max(initial=1)
                                for k in frames) if movie and color == "cluster" else None)
        self.deck = result.deck_name or Path(result.path).stem
        self.caption = run_caption(result)
        self.freq = float(result.parameters.get("freq", 0.0) or 0.0)
        self.strobe = stroboscopic(result.time[frames], self.freq) if movie else 0
        self.size = tuple(int(v) for v in size)
        self.px_per_m = None  # set with the camera
        self.plotter = pv.Plotter(off_screen=True, window_size=list(size))
        self.plotter.set_background(BACKGROUND)
        # No multisampling: with Mesa's software renderer pyvista's default 8x MSAA makes a
        # picture 3-5 times slower for edges hardly smoother at this size.
        self.plotter.ren_win.SetMultiSamples(1)
        self._camera_set = False
        self.legend = None  # --color state's, made at the first frame
        self.state_counts = np.zeros(len(state_palette()), dtype=np.int64)

    def _floor(self, frame: FrameData):
        placed = track_mesh(self.result, frame)
        if placed is not None:
            return placed
        return floor_patch(frame, self.bounds[:4])  # steady under the camera over a movie

    def _part_mesh(self, frame: FrameData):
        """The parts' shapes with their colouring values, and the add_mesh keywords for them."""
        shapes = shape_mesh(frame, self.shape)
        owner = shapes.owner
        mesh = _polydata(self.pv, shapes.points, shapes.triangles)
        mesh.point_data["Normals"] = shapes.normals
        mesh.point_data.active_normals_name = "Normals"
        if self.part_color is not None:
            return mesh, {"color": self.part_color}
        bar = {"color": "black", "vertical": True, "position_x": 0.9, "position_y": 0.2,
               "width": 0.05, "height": 0.6, "title_font_size": 16, "label_font_size": 14}
        if self.color == "speed":
            mesh.point_data["speed"] = frame.speed[owner] * 1e3
            top = self.speed_top * 1e3
            # Only parts off the track can be faster than the scale (speed_limit).
            faster = int((frame.speed > self.speed_top).sum())
            title = "speed [mm/s]"
            if faster:
                # (the magenta box above the bar, labelled "faster", ends the sentence)
                title += f"\nclipped: {faster} part{'s' if faster > 1 else ''}\noff the track:"
            return mesh, {"scalars": "speed", "cmap": "viridis", "clim": (0.0, top),
                          "above_color": "#ff00ff",
                          "scalar_bar_args": {**bar, "title": title, "fmt": "%.3g",
                                              "above_label": "faster"}}
        if self.color == "state":
            categories = self.states.categories(frame)
            self.state_counts = np.bincount(categories.astype(int), minlength=len(state_palette()))
            mesh.point_data["state"] = categories[owner]
            palette = state_palette()
            # One colour per category, centred on the integers; the legend names them.
            return mesh, {"scalars": "state", "cmap": [c for _, c in palette],
                          "clim": (-0.5, len(palette) - 0.5), "n_colors": len(palette),
                          "show_scalar_bar": False}
        sizes = _cluster_sizes(self.result, frame)
        mesh.point_data["cluster size"] = sizes[owner]
        top = int(max(self.cluster_top or sizes.max(initial=1), 3))
        # One colour per size, centred on the integers; single parts fall below the scale
        # and take the grey below_color.
        style = {"scalars": "cluster size", "cmap": "plasma", "clim": (1.5, top + 0.5),
                 "below_color": SINGLE_COLOR, "n_colors": top - 1,
                 "scalar_bar_args": {**bar, "title": "parts per cluster", "fmt": "%.0f",
                                     "below_label": "1"}}
        if top <= 16:
            style["annotations"] = {float(s): str(s) for s in range(2, top + 1)}
            style["scalar_bar_args"]["n_labels"] = 0
        return mesh, style

    def legend_labels(self) -> list[str]:
        """--color state's legend: each category and how many parts of the frame are in it."""
        return [f"{label}  {n}" for (label, _), n in zip(state_palette(), self.state_counts)]

    def _state_legend(self) -> None:
        """--color state's legend in the colour bar's place, what counts as correct above it;
        made once, its counts changed with the frame."""
        labels = self.legend_labels()
        if self.legend is None:
            p = self.plotter
            legend = self.legend = p.add_legend(labels, loc=None, name="legend")
            for k, (_, color) in enumerate(state_palette()):
                # the square takes the category's colour from its own cells; the entry's colour
                # left unset (negative), its text is the text property's black
                legend.SetEntry(k, _swatch(self.pv, color), labels[k], [-1.0, -1.0, -1.0])
            legend.GetEntryTextProperty().SetColor(0.0, 0.0, 0.0)
            legend.SetPosition(SCENE_WIDTH + 0.01, 0.3)
            legend.SetPosition2(0.98 - SCENE_WIDTH, 0.36)
            # a line a condition ("|" is not drawn by VTK's text: "or")
            rule = str(self.states.correct).replace(", ", ",\n").replace("|", " or ")
            p.add_text(f"correct:\n{rule}", position=(SCENE_WIDTH + 0.01, 0.68), viewport=True,
                       font_size=max(6, round(9 * min(1.0, self.size[0] / DEFAULT_SIZE[0]))),
                       color="black", name="correct", render=False)
            return
        for k, label in enumerate(labels):
            self.legend.SetEntryString(k, label)

    def _set_camera(self) -> None:
        """Parallel projection square to x, the view bounds fitted into the scene's part of
        the picture (left of the colour bar): ``px_per_m`` pixels per metre along x."""
        lo, hi = self.bounds[0::2], self.bounds[1::2].copy()
        hi[0] += FALL_ROOM * (hi[0] - lo[0])  # the parts falling past the outlet edge stay in view
        w, h = self.size
        direction = VIEW_DIRECTION / np.linalg.norm(VIEW_DIRECTION)
        up = np.array([0.0, 0.0, 1.0]) - direction[2] * direction
        up /= np.linalg.norm(up)
        corners = np.array(np.meshgrid(*zip(lo, hi), indexing="ij")).reshape(3, -1).T
        tall = float(np.ptp(corners @ up))
        # Half the view's height in metres: the taller of the bounds' height and their
        # length scaled to the picture's shape, with room for the title, scale bar and footer.
        scale = 0.5 * max(tall / 0.72, (hi[0] - lo[0]) * h / (SCENE_WIDTH * w * 0.96))
        self.px_per_m = h / (2 * scale)
        centre = (lo + hi) / 2
        # Shift the view right by half the colour bar's share: the scene sits left of the bar.
        centre[0] += 0.5 * (1 - SCENE_WIDTH) * w / self.px_per_m
        camera = self.plotter.camera
        self.plotter.camera_position = [tuple(centre + direction * float(np.linalg.norm(hi - lo))),
                                        tuple(centre), tuple(up)]
        camera.SetParallelProjection(True)
        camera.SetParallelScale(scale)
        self.plotter.reset_camera_clipping_range()
        self._camera_set = True

    def scale_bar(self) -> tuple[float, int]:
        """(length [m], length [px]) of the scale bar: a round length near a fifth of the view."""
        length = nice_length(0.2 * SCENE_WIDTH * self.size[0] / self.px_per_m)
        return length, int(round(length * self.px_per_m))

    def draw(self, frame: FrameData) -> None:
        p = self.plotter
        vertices, triangles = self._floor(frame)
        # render=False everywhere: one render per picture, in image(), not one per actor.
        p.add_mesh(_polydata(self.pv, vertices, triangles), color=TRACK_COLOR, name="track",
                   opacity=TRACK_OPACITY, smooth_shading=False, show_scalar_bar=False, render=False)
        # The bar's title changes with the frame (the parts off the scale): one bar, redrawn.
        for title in list(p.scalar_bars.keys()):
            p.remove_scalar_bar(title, render=False)
        if len(frame):
            mesh, style = self._part_mesh(frame)
            # The mesh brings its normals: no smoothing pass over all the parts' points.
            p.add_mesh(mesh, name="parts", smooth_shading=False, render=False, **style)
        else:
            p.remove_actor("parts", render=False)
            self.state_counts[:] = 0
        if self.states is not None:
            self._state_legend()
        title = f"{self.deck}   t = {frame.time:.4f} s   frame {frame.index}/{frame.n_frames - 1}"
        if self.freq > 0:
            title += f"   phase {frame.time * self.freq % 1:.2f} T"
        title += f"   {len(frame)} parts"
        if self.strobe:
            title += (f"\nstroboscopic: one frame every {self.strobe} vibration period"
                      f"{'s' if self.strobe > 1 else ''} - the track's oscillation is not seen, "
                      "the parts' drift is")
        p.add_text(title, position="upper_left", font_size=11, color="black", name="title",
                   render=False)
        p.add_text(self.caption, position=(MARGIN_PX, 6), font_size=7, color="#404040",
                   name="footer", render=False)
        if not self._camera_set:
            self._set_camera()
            length, px = self.scale_bar()
            p.add_text(f"{length * 1e3:g} mm", position=(MARGIN_PX, BAR_Y_PX + 6), font_size=9,
                       color="black", name="scale", render=False)

    def _paint_bar(self, image: np.ndarray) -> np.ndarray:
        """The scale bar painted into the picture (rows from the top): black, 3 px thick."""
        _, px = self.scale_bar()
        h = image.shape[0]
        row = h - BAR_Y_PX
        image[row - 3:row, MARGIN_PX:MARGIN_PX + px] = 0
        return image

    def image(self) -> np.ndarray:
        """(height, width, 3) uint8 of what is drawn."""
        self.plotter.render()  # screenshot() renders by itself only the first time
        return self._paint_bar(np.array(self.plotter.screenshot(return_img=True)))

    def close(self) -> None:
        self.plotter.close()


def render_frame(result, frame: int = -1, color: str = "speed", size=DEFAULT_SIZE,
                 part_color=None, correct=None) -> np.ndarray:
    """(height, width, 3) uint8 picture of one frame; ``part_color`` (a colour name or
    ``#rrggbb``) paints every part in that colour instead of ``color``'s scale. ``correct``:
    what --color state counts as correctly oriented (words or a Correct; default
    "up, lengthwise")."""
    data = read_frame(result, frame)
    painter = _Painter(result, color, size, np.array([data.index]), part_color, correct)
    try:
        painter.draw(data)
        return painter.image()
    finally:
        painter.close()


def _ffmpeg() -> str:
    found = shutil.which("ffmpeg")
    if found is None:
        raise OutputError("writing MP4 needs ffmpeg on the PATH: apt-get install ffmpeg")
    return found


def write_whole(path, data) -> Path:
    """Write ``data`` (bytes) to ``path`` through a temporary name beside it, renamed once
    written: a full disk is an :class:`OSError` from Python (errno ENOSPC) and leaves neither
    a cut file under ``path`` nor the temporary one; an older file at ``path`` is kept."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.part")
    try:
        with open(tmp, "wb") as f:
            f.write(data)  # (close flushes: its ENOSPC is raised too)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def _write_png(image: np.ndarray, path: Path) -> None:
    """Write an RGB image as PNG through VTK (already loaded for the drawing).

    VTK encodes into memory and Python writes the bytes: VTK's own file writing meets a
    full disk by printing libpng's "Write Error" on stderr and leaving a cut file."""
    from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkIOImage import vtkPNGWriter

    h, w, c = image.shape
    data = vtkImageData()
    data.SetDimensions(w, h, 1)
    pixels = numpy_to_vtk(np.ascontiguousarray(image[::-1]).reshape(-1, c), deep=True)
    data.GetPointData().SetScalars(pixels)
    writer = vtkPNGWriter()
    writer.WriteToMemoryOn()
    writer.SetInputData(data)
    writer.Write()
    encoded = writer.GetResult()
    if encoded is None or encoded.GetNumberOfTuples() == 0:
        raise OutputError(f"VTK could not encode the picture for {path}")
    write_whole(path, vtk_to_numpy(encoded).tobytes())


def ffmpeg_error(stderr: str) -> str:
    """The line of ffmpeg's error output that says what went wrong: the first one (ffmpeg
    names the cause first, then its consequences, down to "Error initializing output
    stream 0:0 --" or "Conversion failed!"), without ffmpeg's guess "(incorrect codec
    parameters ?)" where the line names the real cause after it."""
    for line in stderr.splitlines():
        line = " ".join(line.split())
        if line:
            return re.sub(r" \([^()]*\?\)(?=:)", "", line)
    return "?"


def _write_mp4(painter: _Painter, frames: np.ndarray, path: Path, fps: float, size, progress) -> None:
    import subprocess

    w, h = size
    cmd = [_ffmpeg(), "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24",
           "-s", f"{w}x{h}", "-r", f"{fps:g}", "-i", "-", "-an", "-vcodec", "libx264",
           "-pix_fmt", "yuv420p", "-crf", "20", str(path)]
    proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        for k in frames:
            painter.draw(read_frame(painter.result, int(k)))
            image = painter.image()
            if image.shape[:2] != (h, w):  # the window may round its size: crop/pad to the stream's
                canvas = np.full((h, w, 3), 255, dtype=np.uint8)
                hh, ww = min(h, image.shape[0]), min(w, image.shape[1])
                canvas[:hh, :ww] = image[:hh, :ww]
                image = canvas
            proc.stdin.write(np.ascontiguousarray(image[:, :, :3]).tobytes())
            if progress:
                progress(1)
        proc.stdin.close()
    except BrokenPipeError:
        pass
    err = proc.stderr.read().decode(errors="replace")
    if proc.wait() != 0:
        raise OutputError(f"ffmpeg could not write {path}: {ffmpeg_error(err)}")


def _size(size) -> tuple[int, int]:
    w, h = (int(x) for x in size)
    if w < 16 or h < 16 or w > 8192 or h > 8192:
        raise UsageError(f"picture size {w}x{h} must be between 16 and 8192 pixels a side")
    return w, h


def render(result, output, frame: int = -1, color: str = "speed", size=DEFAULT_SIZE,
           every: int = 1, fps: float = 25.0, part_color=None, progress=None, correct=None) -> Rendered:
    """Write ``output``: a PNG of frame ``frame`` (.png) or an MP4 of every ``every``-th
    frame at ``fps`` frames per second (.mp4). ``progress(n)`` is called per movie frame;
    ``correct``: what --color state counts as correctly oriented (:func:`render_frame`)."""
    output = Path(output)
    suffix = output.suffix.lower()
    if suffix not in (".png", ".mp4"):
        raise UsageError(f"output {output} must end in .png (one frame) or .mp4 (a movie)")
    if every < 1 or fps <= 0:
        raise UsageError(f"--every must be >= 1 and --fps > 0, got {every} and {fps:g}")
    w, h = _size(size)
    if not output.parent.is_dir():
        raise OutputError(f"cannot write {output}: folder {output.parent} does not exist")
    start = _time.perf_counter()
    if suffix == ".png":
        _write_png(render_frame(result, frame, color, (w, h), part_color, correct), output)
        return Rendered(output, 1, (w, h), _time.perf_counter() - start)
    w, h = w + (-w % 16), h + (-h % 16)  # H.264 in yuv420p wants even sizes; 16 avoids rescaling
    frames = np.arange(0, result.n_frames, every)
    if len(frames) == 0:
        raise UsageError(f"{result.path} has no frames to draw")
    painter = _Painter(result, color, (w, h), frames, part_color, correct)
    try:
        _write_mp4(painter, frames, output, fps, (w, h), progress)
    finally:
        painter.close()
    note = ""
    if painter.strobe:
        note = (f"the frames drawn fall every {painter.strobe} vibration period"
                f"{'s' if painter.strobe > 1 else ''}: the movie is stroboscopic (the track's "
                "oscillation is not seen, the parts' drift is); to see the vibration, run with "
                f"-p output_dt={1 / (8 * painter.freq):.3g} (8 frames per period)")
    return Rendered(output, len(frames), (w, h), _time.perf_counter() - start, note)
