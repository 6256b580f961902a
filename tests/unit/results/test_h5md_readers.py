"""Result files are H5MD 1.1 to the letter, and the users' H5MD readers open a bulk result.

pyh5md reads the result file itself; MDAnalysis (which knows no length unit
``m``) and znh5md/ASE (which expect the parts present first at each frame)
read the ``vibrofeed export --format h5md-md`` file. Each reader's values are
compared with what the writer was given, at the quantity's scale.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import h5py
import numpy as np
import pytest

from bulk_synthetic import feeder
from helpers import vibrofeed
from vibrofeed.results import layout as L
from vibrofeed.results.check import check_file
from vibrofeed.results.md_export import export_md
from vibrofeed.results.reader import Result

FRAMES = np.linspace(0.0, 1.0, 21)
# Parts 1..8 leave at these times: the early ones free slots below parts still present, and
# later ones enter: the particle axis has holes.
EXITS = np.array([0.12, 0.33, 0.41, 0.55, 0.62, 0.9, 1.4, 1.9])
RTOL = 1e-12  # unit conversions by powers of ten, in float64


@pytest.fixture
def bulk(tmp_path):
    """A synthetic bulk result (tests/bulk_synthetic.py) with holes in its slot axis."""
    path = feeder(tmp_path / "feed.h5", FRAMES, EXITS, speed=0.03, amp=2e-5)
    with Result(path) as r:
        ids = r.ids
    live = ids != L.ID_FILL
    holes = [k for k in range(len(ids)) if live[k].any()
             and not live[k, :np.nonzero(live[k])[0].max() + 1].all()]
    assert holes, "the fixture must have a frame with a free slot below an occupied one"
    return path


def present_sorted(r, k, name, ids_in_frame):
    """(ids ascending, values) of the parts present at frame k."""
    f = r.frame(k, fields=(name,))
    order = np.argsort(f.ids)
    assert np.array_equal(np.sort(f.ids), ids_in_frame[np.argsort(ids_in_frame)])
    return f.ids[order], f[name][order]


def is_vlen_ascii(attrs, name):
    info = h5py.check_string_dtype(attrs.get_id(name).dtype)
    return info is not None and info.length is None and info.encoding == "ascii"


def is_fixed(attrs, name):
    info = h5py.check_string_dtype(attrs.get_id(name).dtype)
    return info is not None and info.length is not None


def test_result_follows_h5md_and_its_units_module(bulk):
    with h5py.File(bulk, "r") as f:
        units = f["h5md/modules/units"]
        assert units.attrs["version"].tolist() == [1, 0] and is_vlen_ascii(units.attrs, "system")
        assert units.attrs["system"] == "SI"
        for group, attr in (("h5md/author", "name"), ("h5md/creator", "name"),
                            ("h5md/creator", "version"), (f"{L.PARTS}/box", "boundary")):
            assert is_fixed(f[group].attrs, attr), (group, attr)
        box = f[f"{L.PARTS}/box"]
        assert box.attrs["dimension"] == 3 and [b.decode() for b in box.attrs["boundary"]] == ["none"] * 3
        # edges: a time series whose step and time are the positions' (hard links)
        assert box["edges/step"] == f[f"{L.PARTS}/position/step"]
        assert box["edges/time"] == f[f"{L.PARTS}/position/time"]
        assert box["edges/value"].shape == (len(FRAMES), 3)
        units_seen = {}

        def visit(name, obj):  # the deck's variables keep the deck's notation (parameters)
            if isinstance(obj, h5py.Dataset) and "unit" in obj.attrs and not name.startswith(L.VARIABLES):
                assert is_vlen_ascii(obj.attrs, "unit"), name
                units_seen[name] = obj.attrs["unit"]
        f.visititems(visit)
        assert units_seen[f"{L.PARTS}/velocity/value"] == "m s-1"
        assert units_seen[f"{L.PARTS}/angular_velocity/value"] == "rad s-1"
        assert len(units_seen) >= 10  # hard-linked step/time are visited once
        time = f[f"{L.PARTS}/position/time"]
        assert time.attrs["unit"] == "s" and is_vlen_ascii(time.attrs, "unit")
        # every observable is a time series; the event table lives outside observables
        leaves = []
        f["observables"].visititems(lambda n, o: leaves.append(n) if isinstance(o, h5py.Dataset) else None)
        assert leaves and all(n.rsplit("/", 1)[1] in ("step", "time", "value") for n in leaves), leaves
        assert L.OUTLET in f and "outlet" not in f["observables"]
        assert f[L.PARAMETERS].attrs["format_version"].tolist() == list(L.FORMAT_VERSION)
    assert check_file(bulk).ok


def as_format_1_2(path):
    """Rewrite a result as format 1.2 wrote it: outlet under observables, fixed-length units."""
    with h5py.File(path, "r+") as f:
        f.move(L.OUTLET, L.OUTLET_BEFORE_1_3)
        del f["vibrofeed"]
        del f[f"{L.PARTS}/box/edges"]
        f[L.PARAMETERS].attrs["format_version"] = np.array([1, 2], dtype="i4")
        f["h5md/modules/units"].attrs["system"] = np.bytes_(b"SI")

        def fix(name, obj):
            if "unit" in obj.attrs:
                obj.attrs["unit"] = np.bytes_(obj.attrs["unit"].encode())
        f.visititems(fix)


def test_files_of_format_1_2_still_read(bulk, tmp_path):
    old = tmp_path / "old.h5"
    old.write_bytes(bulk.read_bytes())
    as_format_1_2(old)
    with Result(bulk) as new, Result(old) as r:
        assert r.outlet_plane == new.outlet_plane and r.outlet_plane is not None
        for name, values in new.outlet.items():
            np.testing.assert_array_equal(r.outlet[name], values)  # the same stored numbers
        assert len(r.outlet["id"]) == int((EXITS <= FRAMES[-1]).sum())
    report = check_file(old)
    assert report.ok, [str(p) for p in report.problems]
    a, b = vibrofeed("feedrate", bulk, "--json"), vibrofeed("feedrate", old, "--json")
    assert a.returncode == b.returncode and a.stdout  # the synthetic run may have too few exits (exit 1)
    assert a.stdout.replace(str(bulk), "") == b.stdout.replace(str(old), "")


def test_pyh5md_reads_the_result_file(bulk):
    pyh5md = pytest.importorskip("pyh5md")
    with pyh5md.File(str(bulk), "r") as f, Result(bulk) as r:
        parts = f["particles/parts"]
        position = pyh5md.element(parts, "position")
        assert position.element_type == "TimeElement"
        np.testing.assert_array_equal(position.step[()], r.step)
        np.testing.assert_allclose(position.time[()], FRAMES, rtol=RTOL, atol=0)
        ids = pyh5md.element(parts, "id").value[()]
        np.testing.assert_array_equal(ids, r.ids)
        x = position.value[()]
        live = ids != L.ID_FILL
        # part k + 1 rides the track at 0.03 m/s toward the edge at x = 0.02 m (+- 20 um of
        # vibration) until it leaves
        k = 3
        slot = np.nonzero(ids[k] == 4)[0][0]
        expected = 0.02 - 0.03 * (EXITS[3] - FRAMES[k])
        assert abs(x[k, slot, 0] - expected) <= 2.1e-5
        assert np.isnan(x[~live]).all() and np.isfinite(x[live]).all()
        edges = pyh5md.element(parts["box"], "edges")
        np.testing.assert_array_equal(edges.step[()], r.step)


@pytest.fixture
def exported(bulk, tmp_path):
    proc = vibrofeed("export", bulk, "--format", "h5md-md", "-o", tmp_path / "md", check=True)
    path = tmp_path / "md" / "feed.h5md"
    assert str(path) in proc.stdout and path.exists()
    assert not (tmp_path / "md" / "feed.h5md.part").exists()
    return path


def test_mdanalysis_reads_the_h5md_md_export(bulk, exported):
    mda = pytest.importorskip("MDAnalysis")
    u = mda.Universe(str(exported))  # topology from the file alone: particles/trajectory
    with Result(bulk) as r:
        present = r.present()
        assert u.trajectory.n_frames == len(FRAMES) and u.atoms.n_atoms == present.max()
        assert u.trajectory.units["length"] == "nm" and u.trajectory.units["time"] == "s"
        with h5py.File(exported, "r") as f:
            row_ids = f["particles/trajectory/id/value"][()]
        for k, ts in enumerate(u.trajectory):
            # MDAnalysis converts to its units: Angstrom, ps, Angstrom/ps
            assert ts.time == pytest.approx(FRAMES[k] * 1e12, rel=RTOL)
            n = present[k]
            ids, x = present_sorted(r, k, "position", row_ids[k, :n])
            np.testing.assert_array_equal(row_ids[k, :n], ids)
            np.testing.assert_allclose(ts.positions[:n], x * 1e10, rtol=1e-6, atol=0)  # float32
            assert np.isnan(ts.positions[n:]).all()
            _, v = present_sorted(r, k, "velocity", row_ids[k, :n])
            np.testing.assert_allclose(ts.velocities[:n], v * 1e-2, rtol=1e-6, atol=1e-12)
            assert ts.data["mass_balance/exited"] == r.mass_balance["exited"][k]
            np.testing.assert_allclose(ts.data["surface/position"],
                                       r.surface_position[k] * 1e9, rtol=RTOL, atol=1e-9)


def test_znh5md_reads_the_h5md_md_export(bulk, exported):
    znh5md = pytest.importorskip("znh5md")
    io = znh5md.IO(str(exported), variable_shape=False)
    assert len(io) == len(FRAMES)
    with Result(bulk) as r:
        present = r.present()
        for k in (0, 4, len(FRAMES) - 1):
            atoms = io[k]
            ids = atoms.arrays["id"]
            n = present[k]
            assert (ids[:n] >= 1).all() and (ids[n:] == L.ID_FILL).all()
            _, x = present_sorted(r, k, "position", ids[:n])
            np.testing.assert_allclose(atoms.positions[:n], x * 1e9, rtol=RTOL, atol=0)  # nm
            assert (atoms.numbers[:n] == 1).all() and (atoms.numbers[n:] == 0).all()
            assert not atoms.pbc.any()
            _, m = present_sorted(r, k, "mass", ids[:n])
            np.testing.assert_allclose(atoms.get_masses()[:n], m, rtol=RTOL, atol=0)


def test_export_leaves_out_what_the_result_does_not_record(tmp_path):
    """Clumps have no per-part force (NaN by design): the export has no force element."""
    path = feeder(tmp_path / "clumps.h5", FRAMES[:5], EXITS)
    with h5py.File(path, "r+") as f:
        f[f"{L.PARTS}/force/value"][...] = np.nan
    with Result(path) as r:
        out = export_md(r, tmp_path / "clumps.h5md", every=2)
    with h5py.File(out, "r") as f:
        group = f["particles/trajectory"]
        assert "force" not in group and "velocity" in group
        assert group["position/value"].shape[0] == 3  # frames 0, 2, 4
        np.testing.assert_allclose(group["position/time"][()], FRAMES[:5:2], rtol=RTOL, atol=0)


def test_export_refuses_options_of_the_other_format(bulk, tmp_path):
    proc = vibrofeed("export", bulk, "--format", "h5md-md", "--no-shapes", "-o", tmp_path / "x")
    assert proc.returncode == 2 and "--no-shapes" in proc.stderr
    assert not (tmp_path / "x").exists()


# -- a disk that fills while the export is written ------------------------------------------
def disk_of(monkeypatch, room: int, errno_=None):
    """The export's writes (os.pwrite) meet a full disk after ``room`` bytes, as the kernel
    does: a write cut at the limit, then ENOSPC (``errno_``: another error instead)."""
    import errno
    import os

    real = os.pwrite
    written = [0]

    def pwrite(fd, data, offset):
        allowed = room - written[0]
        if allowed <= 0:
            code = errno_ or errno.ENOSPC
            raise OSError(code, os.strerror(code))
        n = real(fd, memoryview(data)[:allowed], offset)
        written[0] += n
        return n

    monkeypatch.setattr(os, "pwrite", pwrite)


@pytest.mark.parametrize("share", [0.0, 0.01, 0.3, 0.9, 0.999])
def test_an_export_meeting_a_full_disk_is_one_error_and_no_file(bulk, tmp_path, monkeypatch, share):
    """Wherever HDF5 is when the disk fills (its superblock, the parts' blocks, the metadata
    written at closing), the export is an OutputError and no file: HDF5 writing to the disk
    itself prints error stacks and then crashes the process."""
    from vibrofeed.cli.outputs import mount_point
    from vibrofeed.errors import OutputError

    with Result(bulk) as r:
        size = export_md(r, tmp_path / "whole.h5md").stat().st_size
        disk_of(monkeypatch, int(share * size))
        out = tmp_path / "cut.h5md"
        with pytest.raises(OutputError, match=f"cannot write {out}: no space left on "
                                              f"{mount_point(tmp_path)}$"):
            export_md(r, out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["feed.h5", "whole.h5md"]


def test_an_export_meeting_another_disk_error_names_it(bulk, tmp_path, monkeypatch):
    import errno

    from vibrofeed.errors import OutputError

    disk_of(monkeypatch, 50_000, errno.EIO)
    with Result(bulk) as r, pytest.raises(OutputError, match="cut.h5md: Input/output error"):
        export_md(r, tmp_path / "cut.h5md")
    assert not (tmp_path / "cut.h5md").exists() and not (tmp_path / "cut.h5md.part").exists()


def test_an_export_is_refused_before_writing_when_the_parts_data_cannot_fit(bulk, tmp_path,
                                                                             monkeypatch):
    from vibrofeed.errors import OutputError
    from vibrofeed.results import md_export

    monkeypatch.setattr(md_export, "free_bytes", lambda folder: 1000)
    monkeypatch.setattr(md_export, "_Sink", None)  # (must not be reached)
    with Result(bulk) as r, pytest.raises(OutputError, match=r"no space left on .* \(the export needs "
                                                              r"at least 0\.\d+ MB, 0\.001 MB free\)"):
        export_md(r, tmp_path / "x.h5md")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["feed.h5"]


# -- each reader's default mode, and the recipes of the export's own docs ---------------------
DOCS = Path(__file__).resolve().parents[3] / "docs" / "commands.md"


def recipes() -> list[str]:
    """The Python blocks of docs/commands.md's "Reading an h5md-md export", in order."""
    text = DOCS.read_text()
    section = text.split("### Reading an h5md-md export", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, flags=re.S)


def run_recipe(code: str, export: Path) -> dict:
    assert "md/RUN.h5md" in code
    namespace: dict = {}
    exec(compile(code.replace("md/RUN.h5md", str(export)), str(DOCS), "exec"), namespace)
    return namespace


def test_the_export_docs_mdanalysis_recipe_gives_each_frame_its_parts_and_masses(bulk, exported):
    mdanalysis, _ = recipes()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # (MDAnalysis: no types to guess masses from)
        ns = run_recipe(mdanalysis, exported)
    u, ids, mass = ns["u"], ns["ids"], ns["mass"]
    with Result(bulk) as r:
        present = r.present()
        last = len(FRAMES) - 1
        # the recipe's loop ends at the last frame: its parts, their masses, their centre
        x = present_sorted(r, last, "position", ids[last, :present[last]])[1]
        _, m = present_sorted(r, last, "mass", ids[last, :present[last]])
        assert len(ns["parts"]) == present[last]
        np.testing.assert_allclose(ns["parts"].masses, m, rtol=RTOL, atol=0)
        np.testing.assert_allclose(ns["centre"], (m[:, None] * x).sum(0) / m.sum() * 1e10, rtol=1e-6)
        for k, ts in enumerate(u.trajectory):  # and every frame as the recipe reads it
            u.atoms.masses = mass[ts.frame]
            parts = u.atoms[ids[ts.frame] >= 0]
            ids_k, m = present_sorted(r, k, "mass", ids[k, :present[k]])
            assert len(parts) == present[k] and np.array_equal(ids[k, :present[k]], ids_k)
            np.testing.assert_allclose(parts.masses, m, rtol=RTOL, atol=0)
            assert np.isfinite(parts.positions).all() and u.trajectory.ts.dimensions is None  # open box


def test_the_export_docs_znh5md_recipe_gives_the_parts_present_their_masses_and_an_open_box(
        bulk, exported):
    _, znh5md_recipe = recipes()
    ns = run_recipe(znh5md_recipe, exported)
    with Result(bulk) as r:
        last = len(FRAMES) - 1
        parts = ns["parts"]
        ids, m = present_sorted(r, last, "mass", parts.arrays["id"])
        assert len(parts) == r.present()[last] and np.array_equal(parts.arrays["id"], ids)  # ascending
        np.testing.assert_allclose(parts.get_masses(), m, rtol=RTOL, atol=0)
        assert not parts.pbc.any()


def test_znh5md_reads_the_result_file_as_the_export_docs_say(bulk):
    """variable_shape=False, then id >= 0: the parts present at each frame, whatever their slots,
    their masses, and the box open (box/pbc: without it znh5md read the box as periodic)."""
    import znh5md

    io = znh5md.IO(str(bulk), variable_shape=False)
    with Result(bulk) as r:
        present = r.present()
        for k in range(len(FRAMES)):
            atoms = io[k]
            parts = atoms[atoms.arrays["id"] >= 0]
            assert len(parts) == present[k]
            ids, x = present_sorted(r, k, "position", parts.arrays["id"])
            order = np.argsort(parts.arrays["id"])
            np.testing.assert_array_equal(parts.positions[order], x)  # m, as stored
            _, m = present_sorted(r, k, "mass", parts.arrays["id"])
            np.testing.assert_array_equal(parts.get_masses()[order], m)
            assert not atoms.pbc.any()


@pytest.fixture
def steady(tmp_path):
    """A result whose three parts are on the track at every frame (they leave after the last):
    no padding, no empty slot."""
    path = feeder(tmp_path / "steady.h5", FRAMES, np.array([1.2, 1.5, 1.9]), speed=0.01,
                  mass=np.array([1e-7, 2e-7, 3e-7]))
    with Result(path) as r:
        assert (r.present() == 3).all()
    return path


def test_znh5md_default_mode_reads_a_result_and_its_export_whose_parts_stay(steady, tmp_path):
    import znh5md

    export = vibrofeed("export", steady, "--format", "h5md-md", "-o", tmp_path / "md", check=True)
    assert export.returncode == 0
    for path, scale in ((steady, 1.0), (tmp_path / "md" / "steady.h5md", 1e9)):
        io = znh5md.IO(str(path))  # the default mode: variable_shape=True
        assert len(io) == len(FRAMES)
        with Result(steady) as r:
            for k in range(len(FRAMES)):
                atoms = io[k]
                ids, x = present_sorted(r, k, "position", atoms.arrays["id"])
                order = np.argsort(atoms.arrays["id"])
                assert len(atoms) == 3 and np.array_equal(atoms.arrays["id"][order], [1, 2, 3])
                np.testing.assert_allclose(atoms.positions[order], x * scale, rtol=RTOL, atol=0)
                np.testing.assert_array_equal(atoms.get_masses()[order], [1e-7, 2e-7, 3e-7])
                assert not atoms.pbc.any(), path  # the box is open


def test_znh5md_default_mode_cannot_read_parts_that_come_and_go_as_the_export_docs_say(exported):
    """H5MD stores species as Enumeration or Integer (H5MD 1.1, "Particles group"): no NaN to mark
    padding, which znh5md's default mode trims by. The export's docs say so and give the way;
    this test keeps them true (a znh5md that reads it would fail it: then say so in the docs)."""
    import znh5md

    with h5py.File(exported, "r") as f:
        group = f["particles/trajectory"]
        assert group["species/value"].dtype.kind == "i" and group["id/value"].dtype.kind == "i"
        assert group["id/value"].fillvalue == L.ID_FILL  # H5MD: "the particle is considered non-existing"
        assert (group["id/value"][()] == L.ID_FILL).any()
    with pytest.raises(ValueError, match=r'Array "positions" has wrong shape \(\d+, 3\) != \(\d+, 3\)'):
        znh5md.IO(str(exported))[len(FRAMES) - 1]
    assert 'Array "positions" has wrong shape (3, 3) != (14, 3)' in DOCS.read_text()
