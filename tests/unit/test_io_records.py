"""Records and results on disk: CSV and HDF5 round trips, bad input, atomic writes."""

import os
import re
from datetime import datetime
from pathlib import Path

import h5py
import numpy as np
import pytest

import bwim
from bwim import io
from bwim import scenario as scn
from bwim.errors import InputError
from bwim.records import VBIConvergence

SENSORS = (
    bwim.Sensor(x=6.0, y=4.0, kind="strain_x", name="a"),
    bwim.Sensor(x=6.0, y=4.0, kind="deflection", name="b"),
    bwim.Sensor(x=3.0, y=2.0, kind="strain_y"),  # default name "strain_y@3,2" has a comma
)


def raises(message: str):
    return pytest.raises(InputError, match="^" + re.escape(message) + "$")


CLOCK = datetime(2015, 10, 1, 9, 45, 52, 576000)


def synthetic_record(rng, *, truths=True, clock=CLOCK) -> bwim.Record:
    t = 0.001 * np.arange(50)
    passages = (
        bwim.Passage(speed=20.0, lane=2.0, axle_spacings=[5.5], track_width=2.0, delay=0.0),
        bwim.Passage(speed=17.3, lane=5.1, axle_spacings=[3.6, 1.3], track_width=None,
                     delay=0.0123),
    )
    tr = ()
    if truths:
        tr = tuple(
            bwim.Truth(wheel_forces=rng.normal(size=(50, 2 * p.n_axles)),
                       axle_forces=rng.normal(size=(50, p.n_axles)),
                       static_wheel_loads=rng.uniform(1, 2, 2 * p.n_axles),
                       static_axle_loads=rng.uniform(1, 2, p.n_axles),
                       contact_lost=rng.uniform(size=2 * p.n_axles) < 0.5)
            for p in passages
        )
    return bwim.Record(time=t, data=rng.normal(size=(50, 3)) * 1e-5, sensors=SENSORS,
                       passages=passages, truths=tr,
                       convergence=VBIConvergence(method="iterative", iterations=7,
                                                  change=3.2e-7, converged=False),
                       settings=bwim.SimulationSettings(approach=37.5, tail=0.125),
                       clock=clock)


def assert_same_passage(p, q):
    assert (p.speed, p.lane, p.track_width, p.delay) == (q.speed, q.lane, q.track_width, q.delay)
    assert np.array_equal(p.axle_spacings, q.axle_spacings)


def assert_same_sensors(a, b):
    assert [(s.name, s.x, s.y, s.kind) for s in a] == [(s.name, s.x, s.y, s.kind) for s in b]


def assert_same_record(r, q):
    assert np.array_equal(r.time, q.time) and np.array_equal(r.data, q.data)
    assert_same_sensors(r.sensors, q.sensors)
    assert len(r.passages) == len(q.passages)
    for p, pp in zip(r.passages, q.passages, strict=True):
        assert_same_passage(p, pp)
    assert len(r.truths) == len(q.truths)
    for t, tt in zip(r.truths, q.truths, strict=True):
        for name in ("wheel_forces", "axle_forces", "static_wheel_loads", "static_axle_loads",
                     "contact_lost"):
            a, b = getattr(t, name), getattr(tt, name)
            assert a.dtype == b.dtype and np.array_equal(a, b)
    assert r.convergence == q.convergence
    assert r.settings == q.settings
    assert r.clock == q.clock


# --- CSV -------------------------------------------------------------------------------------
def test_csv_round_trip_is_exact_and_columns_follow_the_sensors(tmp_path, rng):
    rec = synthetic_record(rng, truths=False, clock=None)
    path = tmp_path / "rec.csv"
    io.write_csv_record(rec, path)
    assert path.read_text().splitlines()[0] == 'time,a,b,"strain_y@3,2"'
    back = io.read_csv_record(path, SENSORS, rec.passages)
    assert np.array_equal(back.time, rec.time) and np.array_equal(back.data, rec.data)
    assert_same_passage(back.passages[1], rec.passages[1])
    swapped = io.read_csv_record(path, SENSORS[::-1], rec.passages[0])
    assert np.array_equal(swapped.data, rec.data[:, ::-1])
    assert back.truths == () and back.convergence is None


def test_csv_logger_conventions(tmp_path):
    p = tmp_path / "log.csv"
    p.write_text("\ufeff# logger 42, units µε\ntime; a ;b\n0.0;1;2\n# pause\n0.5;3;4\n\n",
                 encoding="utf-8")
    rec = io.read_csv_record(p, SENSORS[:2], scale=1e-6)
    assert np.array_equal(rec.time, [0.0, 0.5])
    assert np.allclose(rec.data, [[1e-6, 2e-6], [3e-6, 4e-6]], rtol=0, atol=0)
    p.write_text("t,a,b,extra\n0,1,2,9\n1,3,4,9\n")
    rec = io.read_csv_record(p, SENSORS[:2], time_column="t", allow_extra=True)
    assert rec.data.shape == (2, 2)


@pytest.mark.parametrize(("text", "message"), [
    ("", "the file is empty"),
    ("# only a comment\n\n", "the file is empty"),
    ("time,a,b\n", "no data rows after the header"),
    ("time,a,b\n0,1,2\n", "a record needs at least two samples, got 1"),
    ("time,a\n0,1\n1,2\n", "no column for sensor 'b'; columns: time, a"),
    ("time,x,y\n0,1,2\n1,2,3\n",
     "no column for sensor 'a' (and 1 more); columns: time, x, y"),
    ("t,a,b\n0,1,2\n1,2,3\n", "no time column 'time'; columns: t, a, b"),
    ("time,a,b,c\n0,1,2,3\n1,2,3,4\n",
     "column 'c' is not a sensor of the scenario (remove it, or allow extra columns)"),
    ("time,a,b\n0,1,2\n0.001,nan,2\n", "line 3, column 'a': NaN sample"),
    ("time,a,b\n0,1,2\n0.001,1,-inf\n", "line 3, column 'b': infinite sample"),
    ("time,a,b\n0,1,2\n0.001,1,\n", "line 3, column 'b': empty cell"),
    ("time,a,b\n0,1,2\n0.001,1,2x\n", "line 3, column 'b': '2x' is not a number"),
    ("time,a,b\n0,1,2\n# note\n0.001,1\n", "line 4 has 2 fields, the header has 3"),
    ("time,a,b\n0,1,2\n0.002,1,2\n0.001,1,2\n",
     "line 4: time 0.001 s does not increase (previous sample 0.002 s)"),
    ("time,a,b\n0,1,2\n0,1,2\n", "line 3: time 0 s does not increase (previous sample 0 s)"),
    ("time,a,a\n0,1,2\n1,2,3\n", "line 1: column 'a' appears twice"),
    ("time,,b\n0,1,2\n1,2,3\n", "line 1: column 2 has no name"),
    ("0,1,2\n1,2,3\n", "line 1: the first line must name the columns, got '0,1,2'"),
])
def test_csv_bad_input(tmp_path, text, message):
    p = tmp_path / "rec.csv"
    p.write_text(text)
    with raises(f"{p}: {message}"):
        io.read_csv_record(p, SENSORS[:2])


@pytest.mark.parametrize(("change", "message"), [
    ("drop", "dropped"),       # a sample missing: a step of 2 ms in a 1 kHz record
    ("jitter", "step"),        # one sample 0.3 ms late
])
def test_csv_non_uniform_time_is_refused(tmp_path, change, message):
    """Issue 14: dropped samples or jittered time put axles in the wrong place (+53 % on
    one axle); a record's time must be uniform within 1 % of its step."""
    t = np.arange(50) * 1e-3
    if change == "drop":
        t = np.delete(t, 20)
    else:
        t[20] += 3e-4
    rows = "\n".join(f"{v:.6f},1,2" for v in t)
    p = tmp_path / "rec.csv"
    p.write_text(f"time,a,b\n{rows}\n")
    with pytest.raises(InputError, match=message):
        io.read_csv_record(p, SENSORS[:2])


def test_csv_time_written_coarsely_is_uniform(tmp_path):
    """512 Hz written with 4 decimals: the steps differ by up to 1e-4 s from rounding,
    more than 1 % of the step, yet the clock is uniform and the record is read."""
    t = np.round(np.arange(100) / 512.0, 4)
    p = tmp_path / "rec.csv"
    p.write_text("time,a,b\n" + "\n".join(f"{v:.4f},1,2" for v in t) + "\n")
    rec = io.read_csv_record(p, SENSORS[:2])
    assert rec.time.size == 100


def test_csv_missing_file_and_sensor_name_clash(tmp_path):
    with raises(f"{tmp_path / 'no.csv'}: no such file"):
        io.read_csv_record(tmp_path / "no.csv", SENSORS)
    with raises("two sensors are named 'a'; CSV columns need distinct names"):
        io.read_csv_record(tmp_path / "no.csv", [SENSORS[0], SENSORS[0]])


# --- HDF5 records --------------------------------------------------------------------------
def test_hdf5_record_round_trip_exact(tmp_path, rng):
    rec = synthetic_record(rng)
    io.write_record(rec, tmp_path / "r.h5")
    assert_same_record(io.read_record(tmp_path / "r.h5"), rec)
    bare = bwim.Record(time=rec.time, data=rec.data, sensors=SENSORS)
    io.write_record(bare, tmp_path / "bare.h5")
    assert_same_record(io.read_record(tmp_path / "bare.h5"), bare)


def test_hdf5_clock_round_trip_and_older_files(tmp_path, rng):
    """Record.clock (to the microsecond) is an ISO attribute; a file without it (as bwim
    wrote before the clock existed: the attribute deleted) reads as None; a damaged one is
    refused naming the file."""
    rec = synthetic_record(rng, clock=datetime(1999, 12, 31, 23, 59, 59, 999999))
    io.write_record(rec, tmp_path / "r.h5")
    with h5py.File(tmp_path / "r.h5", "r") as f:
        assert f.attrs["clock"] == "1999-12-31T23:59:59.999999"
    assert io.read_record(tmp_path / "r.h5").clock == rec.clock
    with h5py.File(tmp_path / "r.h5", "a") as f:
        del f.attrs["clock"]
    assert io.read_record(tmp_path / "r.h5").clock is None
    with h5py.File(tmp_path / "r.h5", "a") as f:
        f.attrs["clock"] = "yesterday"
    with raises(f"{tmp_path / 'r.h5'}: damaged bwim record file (ValueError)"):
        io.read_record(tmp_path / "r.h5")


def test_csv_clock_round_trip(tmp_path, rng):
    """The clock is a '# clock = ISO' line before the header: written, read back, skipped
    by readers that do not know it (read_numeric_csv); no line: None; a bad one refused."""
    rec = synthetic_record(rng, truths=False)
    p = tmp_path / "r.csv"
    io.write_csv_record(rec, p)
    assert p.read_text().splitlines()[0] == "# clock = 2015-10-01T09:45:52.576000"
    assert io.read_csv_record(p, SENSORS).clock == CLOCK
    bare = bwim.Record(time=rec.time, data=rec.data, sensors=SENSORS)
    io.write_csv_record(bare, p)
    assert not p.read_text().startswith("#") and io.read_csv_record(p, SENSORS).clock is None
    lines = p.read_text().splitlines()
    p.write_text("\n".join(["# exported by hand", "#clock=2015-10-01 09:45:52", *lines,
                            "# clock = not read after the header"]) + "\n")
    assert io.read_csv_record(p, SENSORS).clock == datetime(2015, 10, 1, 9, 45, 52)
    p.write_text("\n".join(["# clock = 1 October", *lines]) + "\n")
    with raises(f"{p}: line 1: '1 October' is not an ISO 8601 date and time (the record's "
                "clock)"):
        io.read_csv_record(p, SENSORS)


def test_hdf5_several_records(tmp_path, rng):
    recs = [synthetic_record(rng), synthetic_record(rng, truths=False, clock=None)]
    io.write_records(recs, tmp_path / "rs.h5")
    back = io.read_records(tmp_path / "rs.h5")
    assert len(back) == 2
    for a, b in zip(back, recs, strict=True):
        assert_same_record(a, b)
    with raises(f"{tmp_path / 'rs.h5'}: holds 2 records; read them with read_records"):
        io.read_record(tmp_path / "rs.h5")
    io.write_record(recs[0], tmp_path / "one.h5")
    assert len(io.read_records(tmp_path / "one.h5")) == 1


def test_hdf5_reader_errors(tmp_path, rng):
    with raises(f"{tmp_path / 'none.h5'}: no such file"):
        io.read_record(tmp_path / "none.h5")
    (tmp_path / "text.h5").write_text("not hdf5")
    with raises(f"{tmp_path / 'text.h5'}: not an HDF5 file (or it cannot be read)"):
        io.read_record(tmp_path / "text.h5")
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = 1.0
    with raises(f"{tmp_path / 'other.h5'}: not a bwim file (no bwim_format attribute)"):
        io.read_record(tmp_path / "other.h5")
    io.write_record(synthetic_record(rng), tmp_path / "r.h5")
    with raises(f"{tmp_path / 'r.h5'}: holds a bwim record, not a identification"):
        io.read_identification(tmp_path / "r.h5")
    with h5py.File(tmp_path / "r.h5", "a") as f:
        del f["sensors/name"]
    with raises(f"{tmp_path / 'r.h5'}: damaged bwim record file: /sensors/name is missing"):
        io.read_record(tmp_path / "r.h5")
    with h5py.File(tmp_path / "r.h5", "a") as f:
        f.attrs["bwim_format_version"] = 99
    with raises(f"{tmp_path / 'r.h5'}: format version 99 is newer than this bwim reads (1); "
                "update bwim"):
        io.read_record(tmp_path / "r.h5")


# --- results -------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def beam_crossing():
    beam = bwim.Bridge.beam(length=15.0, n_elements=15, E=3e10, I=0.6, mu=8e3, z_bottom=0.5)
    sensors = [bwim.Sensor(x=x, kind="strain_x", name=f"s{x:g}") for x in (3.75, 7.5, 11.25)]
    vehicle = bwim.MovingForces(axle_loads=[60e3, 100e3], axle_spacings=[4.0])
    rec = bwim.simulate(beam, vehicle, speed=15.0, sensors=sensors, sampling_rate=500.0,
                        approach=0.0)
    return beam, vehicle, rec


def test_identification_round_trip_with_and_without_lcurve(tmp_path, beam_crossing):
    beam, _, rec = beam_crossing
    for lam in ("lcurve", 1e-3):
        ident = bwim.identify_forces(beam, rec, n_modes=3, lam=lam, n_lam=8)
        io.write_identification(ident, tmp_path / "id.h5")
        back = io.read_identification(tmp_path / "id.h5")
        for name in ("time", "wheel_forces", "axle_forces", "axle_weights", "gvw", "fitted",
                     "axle_windows"):
            assert np.array_equal(getattr(back, name), getattr(ident, name)), name
        assert (back.lam, back.lam_scaled, back.unknowns, back.order) == (
            ident.lam, ident.lam_scaled, ident.unknowns, ident.order)
        assert_same_passage(back.passages[0], ident.passages[0])
        assert (ident.lcurve is None) == (lam != "lcurve")
        if ident.lcurve is None:
            assert back.lcurve is None
        else:
            for name in ("lam", "lam_scaled", "residual_norm", "seminorm", "curvature"):
                assert np.array_equal(getattr(back.lcurve, name), getattr(ident.lcurve, name))
            assert (back.lcurve.corner, back.lcurve.corner_scaled) == (
                ident.lcurve.corner, ident.lcurve.corner_scaled)
    assert lam == 1e-3 and back.lcurve is None


def test_static_weights_and_influence_line_round_trip(tmp_path, beam_crossing):
    beam, vehicle, rec = beam_crossing
    line = bwim.calibrate_influence_line([rec], vehicle, channels="each")
    io.write_influence_line(line, tmp_path / "il.h5")
    back = io.read_influence_line(tmp_path / "il.h5")
    assert np.array_equal(back.x, line.x) and np.array_equal(back.ordinates, line.ordinates)
    assert (back.lane, back.track_width, back.source, back.residual) == (
        line.lane, line.track_width, line.source, line.residual)
    assert back.channels == line.channels
    weights = bwim.weigh_static(rec, back, groups=((0,), (1,)))
    io.write_static_weights(weights, tmp_path / "w.h5")
    w = io.read_static_weights(tmp_path / "w.h5")
    for name in ("axle_weights", "time", "measured", "fitted"):
        assert np.array_equal(getattr(w, name), getattr(weights, name))
    assert (w.residual, w.condition, w.groups) == (weights.residual, weights.condition,
                                                   weights.groups)
    assert w.channels == weights.channels
    assert_same_passage(w.passage, weights.passage)
    model_line = bwim.model_influence_line(beam, rec.sensors, channels="sum")
    io.write_influence_line(model_line, tmp_path / "ml.h5")
    back = io.read_influence_line(tmp_path / "ml.h5")
    assert back.residual is None and back.channels == model_line.channels


# --- atomic writes -------------------------------------------------------------------------
def test_unwritable_output_paths(tmp_path, rng):
    rec = synthetic_record(rng)
    missing = tmp_path / "no" / "such" / "r.h5"
    with raises(f"cannot write {missing}: the folder {missing.parent} does not exist"):
        io.write_record(rec, missing)
    with raises(f"cannot write {tmp_path}: it is a folder"):
        io.write_csv_record(rec, tmp_path)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0,
                    reason="permissions are not enforced for root / on this OS")
def test_read_only_folder(tmp_path, rng):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        with raises(f"cannot write {ro / 'r.csv'}: no permission to write in {ro}"):
            io.write_csv_record(synthetic_record(rng), ro / "r.csv")
    finally:
        ro.chmod(0o755)


def test_no_permission_is_reported_before_writing(tmp_path, rng, monkeypatch):
    monkeypatch.setattr(os, "access", lambda path, mode: False)
    with raises(f"cannot write {tmp_path / 'r.h5'}: no permission to write in {tmp_path}"):
        io.write_record(synthetic_record(rng), tmp_path / "r.h5")
    assert list(tmp_path.iterdir()) == []


def test_failure_mid_write_leaves_no_file(tmp_path, rng, monkeypatch):
    rec = synthetic_record(rng)
    out = tmp_path / "out"
    out.mkdir()

    def boom(*args, **kwargs):
        raise RuntimeError("disk on fire")

    def half_written(values):
        yield "0.0,1.0,2.0,3.0\n"  # a first line reaches the file, then the writer fails
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(io.records, "_csv_lines", half_written)
    with pytest.raises(RuntimeError, match="disk on fire"):
        io.write_csv_record(rec, out / "r.csv")
    monkeypatch.undo()
    monkeypatch.setattr(io.records, "_put_truth", boom)  # after time, data, sensors
    with pytest.raises(RuntimeError, match="disk on fire"):
        io.write_record(rec, out / "r.h5")
    assert list(out.iterdir()) == []
    # an existing file is left exactly as it was
    io.write_record(bwim.Record(time=rec.time, data=rec.data, sensors=SENSORS), out / "r.h5")
    before = (out / "r.h5").read_bytes()
    with pytest.raises(RuntimeError, match="disk on fire"):
        io.write_record(rec, out / "r.h5")
    assert (out / "r.h5").read_bytes() == before
    assert sorted(p.name for p in out.iterdir()) == ["r.h5"]


def test_os_error_while_writing_names_the_path(tmp_path, rng, monkeypatch):
    def full(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", full)
    with raises(f"cannot write {tmp_path / 'r.csv'}: no space left on device"):
        io.write_csv_record(synthetic_record(rng), tmp_path / "r.csv")
    assert list(tmp_path.iterdir()) == []


def test_atomic_output_replaces_only_on_success(tmp_path):
    target = tmp_path / "t.txt"
    with io.atomic_open(target) as f:
        f.write("one")
    with pytest.raises(KeyError), io.atomic_open(target) as f:
        f.write("two")
        raise KeyError("x")
    assert target.read_text() == "one"
    assert [p.name for p in tmp_path.iterdir()] == ["t.txt"]
    assert Path(target).stat().st_mode & 0o777 == 0o666 & ~_umask()


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


# --- records for a scenario ------------------------------------------------------------------
def test_load_record_by_extension(tmp_path, rng):
    scenario = scn.load_scenario(Path(__file__).resolve().parents[2] / "examples" / "beam.toml")
    sensors = scn.build_sensors(scenario)
    rec = bwim.Record(time=0.002 * np.arange(20), data=rng.normal(size=(20, 3)),
                      sensors=sensors)
    io.write_csv_record(rec, tmp_path / "log.csv")
    got = scn.load_record(tmp_path / "log.csv", scenario)
    assert np.array_equal(got.data, rec.data)
    assert_same_passage(got.passage, scn.build_passage(scenario))
    # a measured record takes the [run]'s approach; it ends before the vehicle leaves
    assert got.settings == bwim.SimulationSettings(approach=50.0, tail=0.0)
    io.write_record(got, tmp_path / "log.h5")
    assert_same_record(scn.load_record(tmp_path / "log.h5"), got)
    with raises(f"{tmp_path / 'log.csv'}: a CSV record needs a scenario for its sensor "
                "positions"):
        scn.load_record(tmp_path / "log.csv")
    with raises(f"{tmp_path / 'log.xlsx'}: unknown record format '.xlsx'; use .csv or .h5"):
        scn.load_record(tmp_path / "log.xlsx", scenario)
