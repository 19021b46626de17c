"""Logger text files → Record (bwim.io.logger), and sensors without a position.

References: round trips (numbers written with ``repr`` are read back bit for bit, so a
known array is the reference); every refusal is checked by its reason in a one-line
message that names the file; hypothesis fuzzing asserts the reader's contract (a valid
Record or an InputError, never another exception).
"""

import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import bwim
from bwim import io
from bwim.errors import InputError
from bwim.io.logger import LoggerFormat, read_logger
from bwim.sensors import Sensor, SensorKind
from bwim.wim.influence_line import resolve_channels

FS = 512.0
COLUMNS = ("time", "ad1", "ad2", "s01", "s02", "-")
KINDS = {"ad1": "axle_detector", "ad2": "axle_detector"}


def fmt(**kw) -> LoggerFormat:
    args = dict(columns=COLUMNS, kinds=KINDS)
    args.update(kw)
    return LoggerFormat(**args)


def known(rng, n=40, t0=45123.25):
    """Clock time at 512 Hz and four channels of random readings."""
    return t0 + np.arange(n) / FS, rng.normal(size=(n, 4)) * 100.0


def text_of(time, data, *, sep=",", header=True, skip="OK", names=COLUMNS, newline="\n",
            trailing=False, comment=False):
    rows = []
    if comment:
        rows.append("# exported by the logger")
    if header:
        rows.append(sep.join(names))
    for k in range(len(data)):
        fields = [] if time is None else [repr(float(time[k]))]
        fields += [repr(float(v)) for v in data[k]]
        fields.append(skip)
        rows.append(sep.join(fields) + (sep if trailing else ""))
        if comment and k == 3:
            rows.append("   # a comment inside the data")
            rows.append("")
    return newline.join(rows) + newline


def one_line(message: str) -> bool:
    return "\n" not in message and "\r" not in message


# --- round trips ---------------------------------------------------------------------------

@pytest.mark.parametrize("sep", [",", ";", "\t", " "])
@pytest.mark.parametrize("header", [True, False])
@pytest.mark.parametrize("ext", [".txt", ".csv", ".dat"])
def test_round_trip_each_delimiter_header_extension(tmp_path, rng, sep, header, ext):
    """Reference: the written array.  Auto-detected and explicit layouts read it back
    exactly, time unshifted (clock time), channels in column order with their kinds."""
    t, d = known(rng)
    p = tmp_path / f"event{ext}"
    p.write_text(text_of(t, d, sep=sep, header=header))
    for f in (fmt(), fmt(delimiter=sep, header=header)):
        r = read_logger(p, f)
        assert np.array_equal(r.time, t) and np.array_equal(r.data, d)
        assert [s.name for s in r.sensors] == ["ad1", "ad2", "s01", "s02"]
        assert [s.kind.value for s in r.sensors] == ["axle_detector"] * 2 + ["strain_x"] * 2
        assert all(s.x is None and s.y is None for s in r.sensors)
        assert r.passages == () and r.truths == ()


@pytest.mark.parametrize("newline", ["\n", "\r\n", "\r"])
def test_bom_line_endings_trailing_delimiter_comments(tmp_path, rng, newline):
    """Reference: the written array, through a BOM, CRLF/CR, a trailing delimiter on every
    row, '#' comment lines and blank lines; line numbers in messages count every line."""
    t, d = known(rng)
    text = text_of(t, d, sep=";", newline=newline, trailing=True, comment=True)
    p = tmp_path / "event.dat"
    p.write_bytes(b"\xef\xbb\xbf" + text.encode())
    r = read_logger(p, fmt())
    assert np.array_equal(r.time, t) and np.array_equal(r.data, d)
    # a bad row after the comments: line 2 (comment) + 1 header + 4 rows + 2 + k
    lines = text.split(newline)
    lines[11] = lines[11].replace(repr(float(d[7, 2])), "x")
    p.write_bytes(newline.join(lines).encode())
    with pytest.raises(InputError, match=re.escape(f"{p}: line 12, column 's01': 'x' is "
                                                   "not a number")):
        read_logger(p, fmt())


def test_no_time_column_uses_sampling_rate_and_scale(tmp_path, rng):
    """Reference: time = k / sampling_rate; data × scale per channel (a number, a list in
    channel order, or a mapping with 1.0 for unnamed channels)."""
    _, d = known(rng)
    cols = ("ad1", "ad2", "s01", "s02", "-")
    p = tmp_path / "event.txt"
    p.write_text(text_of(None, d, names=cols))
    r = read_logger(p, fmt(columns=cols, sampling_rate=FS, scale=1e-6))
    assert np.array_equal(r.time, np.arange(len(d)) / FS)
    assert np.array_equal(r.data, d * 1e-6)
    per = [1.0, 2.0, 1e-6, -1e-6]
    r = read_logger(p, fmt(columns=cols, sampling_rate=FS, scale=per))
    assert np.array_equal(r.data, d * np.array(per))
    r = read_logger(p, fmt(columns=cols, sampling_rate=FS, scale={"s02": 1e-6}))
    assert np.array_equal(r.data, d * np.array([1.0, 1.0, 1.0, 1e-6]))


def test_sensors_give_positions_and_kinds(tmp_path, rng):
    """Sensors passed by name are the record's sensors (positions kept); others have none."""
    t, d = known(rng)
    p = tmp_path / "e.csv"
    p.write_text(text_of(t, d))
    s01 = Sensor(x=4.5, y=1.0, name="s01")
    r = read_logger(p, fmt(), sensors=[s01])
    assert r.sensors[2] is s01 and r.sensors[3] == Sensor(name="s02")
    r = read_logger(p, fmt(kinds={}), sensors=[Sensor(name="ad1", kind="axle_detector")])
    assert [s.kind.value for s in r.sensors] == ["axle_detector"] + ["strain_x"] * 3


def test_decimal_comma_with_semicolon(tmp_path):
    """Reference: hand-written values; a quoted header, a skipped text column, a preamble."""
    p = tmp_path / "e.csv"
    p.write_text('LOGGER XYZ v2\nstation 7\n"time";"ad1";"s01";"note"\n'
                 "0,0;1,5;-2,25;ok\n0,5;1,0;3e-1;ok\n1,0;0;.5;ok\n")
    f = LoggerFormat(columns=("time", "ad1", "s01", "-"), decimal=",", skip_lines=2)
    r = read_logger(p, f)
    assert np.array_equal(r.time, [0.0, 0.5, 1.0])
    assert np.array_equal(r.data, [[1.5, -2.25], [1.0, 0.3], [0.0, 0.5]])


@pytest.mark.parametrize(
    ("text", "time", "data"),
    [
        ("time,a,b\n0,1,2\n1,3,4\n", [0, 1], [[1, 2], [3, 4]]),          # comma, header
        ("0;1;2\n1;3;4\n", [0, 1], [[1, 2], [3, 4]]),                     # semicolon, none
        ("0\t1\t2\n1\t3\t4\n", [0, 1], [[1, 2], [3, 4]]),                 # tab
        ("  0   1  2\n 1 3    4  \n", [0, 1], [[1, 2], [3, 4]]),          # whitespace runs
        ("Time [s],Ch 1,Ch 2\n0,1,2\n1,3,4\n", [0, 1], [[1, 2], [3, 4]]),  # spaces in names
        ("t a b\n0 1 2\n1 3 4\n", [0, 1], [[1, 2], [3, 4]]),              # header ≠ columns
        ('"t","a","b"\n"0","1","2"\n"1","3","4"\n', [0, 1], [[1, 2], [3, 4]]),  # quoted
        ("time;a;b;\n0;1;2;\n1;3;4;\n", [0, 1], [[1, 2], [3, 4]]),        # trailing ;
        ("0,+1.5e0,-2\n1,.25,3.\n", [0, 1], [[1.5, -2], [0.25, 3]]),      # number forms
    ],
)
def test_auto_detection(tmp_path, text, time, data):
    """Reference: the hand-written numbers of each file."""
    p = tmp_path / "e.txt"
    p.write_text(text)
    r = read_logger(p, LoggerFormat(columns=("time", "a", "b")))
    assert np.array_equal(r.time, time) and np.array_equal(r.data, data)


def test_time_rounded_by_the_file_is_uniform(tmp_path, rng):
    """A 512 Hz clock written to 0.1 ms steps by 1.9 or 2.0 ms (5 % off the median): uniform
    within one unit of the last written decimal, also against sampling_rate = 512.  The
    same clock at full precision with ±60 µs alternating offsets (6 % steps) is refused."""
    _, d = known(rng, n=60)
    t = np.round(45123.25 + np.arange(60) / FS, 4)
    p = tmp_path / "e.txt"
    p.write_text("".join(f"{t[k]:.4f}," + ",".join(map(repr, d[k].tolist())) + ",x\n"
                         for k in range(60)))
    r = read_logger(p, fmt(sampling_rate=FS))
    assert set(np.round(np.diff(t), 6)) == {0.0019, 0.002}
    # the record's times are the clock they were rounded from (least squares; review of
    # stop 33: the median of the rounded steps, 2 ms, gave a rate of 500 Hz for 512)
    # (measured: within 1.9 µs, the rate 1.2e-5 off)
    np.testing.assert_allclose(r.time, 45123.25 + np.arange(60) / FS, rtol=0, atol=5e-6)
    assert r.sampling_rate == pytest.approx(FS, rel=5e-5)
    t2 = 45123.25 + np.arange(60) / FS + (np.arange(60) % 2) * 60e-6
    p.write_text(text_of(t2, d))
    with pytest.raises(InputError, match="non-uniform sampling"):
        read_logger(p, fmt())


# --- refusals ------------------------------------------------------------------------------

GOOD = "time,ad1,ad2,s01,s02,n\n" + "".join(
    f"{k / FS!r},0.{k % 7},{(k * 3) % 5},{np.sin(k):.6f},{np.cos(k):.6f},z\n" for k in range(20))


def _replace_line(text: str, k: int, new: str) -> str:
    lines = text.splitlines()
    lines[k - 1] = new
    return "\n".join(lines) + "\n"


def _row(k: int) -> list[str]:
    return GOOD.splitlines()[k - 1].split(",")


def _with(k: int, j: int, value: str) -> str:
    row = _row(k)
    row[j] = value
    return _replace_line(GOOD, k, ",".join(row))


def _clipped() -> str:
    """GOOD with s01 at 5.0 (its maximum) on lines 6 to 16: 11 consecutive samples."""
    lines = GOOD.splitlines()
    for k in range(6, 17):
        row = lines[k - 1].split(",")
        row[3] = "5.0"
        lines[k - 1] = ",".join(row)
    return "\n".join(lines) + "\n"


BAD = [
    ("", {}, "the file is empty (no data rows)"),
    ("# only a comment\n\n", {}, "the file is empty (no data rows)"),
    ("time,ad1,ad2,s01,s02,n\n", {}, "no data rows after the header"),
    (GOOD.splitlines()[0] + "\n" + GOOD.splitlines()[1] + "\n", {},
     "1 data row; a record needs at least 2 samples"),
    (GOOD, {"min_samples": 50}, "20 data rows; a record needs at least 50 samples"),
    (GOOD, {"max_samples": 10}, "more than max_samples = 10 data rows"),
    (_replace_line(GOOD, 5, ",".join(_row(5)[:-1])), {},
     "line 5 has 5 fields, the format has 6 columns (delimiter ',')"),
    (_replace_line(GOOD, 5, ",".join([*_row(5), "1"])), {},
     "line 5 has 7 fields, the format has 6 columns (delimiter ',')"),
    (_with(5, 3, "abc"), {}, "line 5, column 's01': 'abc' is not a number"),
    (_with(5, 3, "1_000"), {}, "line 5, column 's01': '1_000' is not a number"),
    (_with(5, 3, ""), {}, "line 5, column 's01': empty field"),
    (_with(5, 3, "NaN"), {}, "line 5, column 's01': NaN sample"),
    (_with(5, 2, "-inf"), {}, "line 5, column 'ad2': infinite sample"),
    (_with(5, 2, "1e999"), {}, "line 5, column 'ad2': infinite sample (overflow)"),
    (_with(5, 0, "nan"), {}, "line 5, column 'time': NaN sample"),
    (_with(5, 4, "1" * 65), {}, "line 5, field 5 is longer than max_field = 64 characters"),
    (_replace_line(GOOD, 3, "#" + "x" * 5000), {}, "line 3 is longer than 4096 characters"),
    (_with(5, 0, repr(2 / FS)), {}, "line 5: time 0.00390625 s does not increase (previous "
     "sample 0.00390625 s)"),
    (_with(5, 0, repr(1 / FS)), {}, "line 5: time 0.00195312 s does not increase (previous "
     "sample 0.00390625 s)"),
    (_replace_line(GOOD, 8, ""), {}, "line 9: time step 0.00390625 s after 0.00976562 s is 2 "
     "x the median step 0.00195312 s (a dropped sample)"),
    (_with(5, 0, repr(3.1 / FS)), {}, "line 5: time step 0.00214844 s differs from the median "
     "step 0.00195312 s by more than 0.01 of it (non-uniform sampling)"),
    (GOOD, {"fmt": fmt(sampling_rate=500.0)},
     "the time column steps 0.00195312 s (512 Hz) but sampling_rate is 500 Hz"),
    (_clipped(), {}, "channel 's01' sits at its maximum 5 for 11 consecutive samples from "
     "line 6 (clipped: logger saturation?; clip_run = 10)"),
    ("0,ad1,ad2,s01,s02,n\n" + GOOD.split("\n", 1)[1], {},
     "line 1 is neither a header (it has numbers) nor data (column 'ad1': 'ad1' is not a "
     "number); set the format's header"),
    ("time,ad1,ad2\n" + GOOD.split("\n", 1)[1], {},
     "line 1: no delimiter (';', tab, ',', whitespace) splits it into the 6 columns of the "
     "format"),
    ("time,ad1,ad2,s01,s02\n" + GOOD.split("\n", 1)[1], {"fmt": fmt(delimiter=",")},
     "line 1 has 5 fields, the format has 6 columns"),
    (GOOD, {"fmt": fmt(header=False)}, "line 1, column 'time': 'time' is not a number"),
]


@pytest.mark.parametrize(("text", "kw", "reason"), BAD)
def test_bad_files_are_refused_with_the_reason(tmp_path, text, kw, reason):
    """Each defect gives an InputError: one line, the file first, then the reason."""
    p = tmp_path / "event.txt"
    p.write_text(text)
    kw = dict(kw)
    f = kw.pop("fmt", fmt())
    with pytest.raises(InputError) as exc:
        read_logger(p, f, **kw)
    msg = str(exc.value)
    assert one_line(msg) and msg.startswith(f"{p}: ") and reason in msg, msg


def test_the_good_file_reads_and_clipping_can_be_off(tmp_path):
    """The base of the refusal cases is itself valid; clip_run=None or a longer run accepts
    the clipped file (its 11-sample plateau)."""
    p = tmp_path / "e.txt"
    p.write_text(GOOD)
    assert read_logger(p, fmt()).data.shape == (20, 4)
    p.write_text(_clipped())
    for kw in ({"clip_run": None}, {"clip_run": 12}):
        assert read_logger(p, fmt(), **kw).data.shape == (20, 4)


def test_flat_baseline_and_saturated_detectors_are_not_clipping(tmp_path):
    """A gauge that sits at its minimum most of the time (a quantised baseline, one-sided
    signal) and an axle detector flat at its maximum are not refused."""
    rows = ["time,ad1,ad2,s01,s02,n"]
    for k in range(60):
        s01 = 0.0 if not 20 <= k < 30 else float(k - 19)
        ad = 9.0 if 30 <= k < 50 else 0.0
        rows.append(f"{k / FS!r},{ad},{ad},{s01},{float(np.sin(k))!r},z")
    p = tmp_path / "e.txt"
    p.write_text("\n".join(rows))
    assert read_logger(p, fmt()).data.shape == (60, 4)


def test_file_level_refusals(tmp_path):
    """No file, a directory, a file over max_bytes (refused before reading: its bytes are
    not even UTF-8), and bytes that are not UTF-8."""
    p = tmp_path / "event.txt"
    with pytest.raises(InputError, match=f"^{re.escape(str(p))}: no such file$"):
        read_logger(p, fmt())
    with pytest.raises(InputError, match="is a directory"):
        read_logger(tmp_path, fmt())
    p.write_bytes(b"\xff\xfe" * 100)
    with pytest.raises(InputError, match=re.escape(f"{p}: 200 bytes is more than max_bytes "
                                                   "= 100")):
        read_logger(p, fmt(), max_bytes=100)
    with pytest.raises(InputError, match=re.escape(f"{p}: not UTF-8 text")):
        read_logger(p, fmt())


@pytest.mark.parametrize(
    ("kw", "reason"),
    [
        (dict(columns=[]), "LoggerFormat.columns must be a non-empty list"),
        (dict(columns="time,a"), "LoggerFormat.columns must be a non-empty list"),
        (dict(columns=["time", "a", "a"]), "LoggerFormat.columns: 'a' appears twice"),
        (dict(columns=["time", "time", "a"]), "'time' appears twice"),
        (dict(columns=["time", " a"]), "LoggerFormat.columns[1] must be a non-empty name"),
        (dict(columns=["time", "-"]), "LoggerFormat.columns names no channel"),
        (dict(columns=["a", "b"]), "without a 'time' column the sampling_rate is needed"),
        (dict(sampling_rate=0.0), "LoggerFormat.sampling_rate must be positive"),
        (dict(delimiter="|"), "LoggerFormat.delimiter must be one of"),
        (dict(header="yes"), "LoggerFormat.header must be true, false or None"),
        (dict(decimal=";"), "LoggerFormat.decimal must be '.' or ','"),
        (dict(decimal=",", delimiter=","), "decimal ',' needs a delimiter other than ','"),
        (dict(scale=0.0), "LoggerFormat.scale must be a finite non-zero number"),
        (dict(scale=float("nan")), "LoggerFormat.scale must be a finite non-zero number"),
        (dict(scale=[1.0, 2.0]), "LoggerFormat.scale has 2 factors for 4 channels"),
        (dict(scale={"s09": 1.0}), "LoggerFormat.scale: 's09' is not a channel"),
        (dict(scale={"s01": "1"}), "LoggerFormat.scale['s01'] must be a finite non-zero"),
        (dict(kinds={"time": "strain_x"}), "LoggerFormat.kinds: 'time' is not a channel"),
        (dict(kinds={"ad1": "axle"}), "LoggerFormat.kinds['ad1']: unknown sensor kind 'axle'"),
        (dict(skip_lines=-1), "LoggerFormat.skip_lines must be an integer >= 0"),
    ],
)
def test_bad_formats(kw, reason):
    with pytest.raises(InputError) as exc:
        fmt(**kw)
    assert one_line(str(exc.value)) and reason in str(exc.value)


@pytest.mark.parametrize(
    ("kw", "reason"),
    [
        (dict(sensors=[Sensor(name="s09")]), "sensors: 's09' is not a channel"),
        (dict(sensors=[Sensor(name="ad1")]), "sensors: 'ad1' is a strain_x sensor but the "
         "logger format says axle_detector"),
        (dict(sensors=[Sensor(name="s01"), Sensor(name="s01")]),
         "sensors: two sensors are named 's01'"),
        (dict(sensors=["s01"]), "sensors[0] must be a bwim.Sensor"),
        (dict(max_bytes=0), "max_bytes must be an integer >= 1"),
        (dict(clip_run=1), "clip_run must be an integer >= 2"),
        (dict(time_tolerance=0.5), "time_tolerance must lie in [0, 0.5)"),
    ],
)
def test_bad_arguments(tmp_path, kw, reason):
    p = tmp_path / "e.txt"
    p.write_text(GOOD)
    with pytest.raises(InputError) as exc:
        read_logger(p, fmt(), **kw)
    assert reason in str(exc.value)
    with pytest.raises(InputError, match=re.escape("fmt must be a bwim.io.logger.LoggerFormat")):
        read_logger(p, {"columns": COLUMNS})


# --- fuzzing ---------------------------------------------------------------------------------

FUZZ_FORMATS = [
    LoggerFormat(columns=("time", "a", "b")),
    LoggerFormat(columns=("a", "-", "b"), sampling_rate=100.0, decimal=","),
    LoggerFormat(columns=("time", "a"), delimiter=";", header=False, kinds={"a": "axle_detector"}),
]
ALPHABET = "0123456789.,;\t \n\r-+eE#\"naifNty\x00\ufeffé"


def _check_contract(path, f):
    try:
        r = read_logger(path, f, max_field=30, clip_run=3)
    except InputError as exc:
        assert one_line(str(exc)) and str(exc).startswith(f"{path}: ")
        return
    assert isinstance(r, bwim.Record)
    assert r.data.shape == (r.time.size, len(f.channels)) and r.time.size >= 2
    assert np.all(np.isfinite(r.data)) and np.all(np.diff(r.time) > 0)


@settings(max_examples=300, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=st.text(alphabet=ALPHABET, max_size=300), k=st.integers(0, 2))
def test_fuzz_text(tmp_path, text, k):
    """Random text: a Record or an InputError, never another exception."""
    p = tmp_path / "fuzz.txt"
    p.write_text(text, encoding="utf-8", newline="")
    _check_contract(p, FUZZ_FORMATS[k])


@settings(max_examples=200, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.binary(max_size=300), k=st.integers(0, 2))
def test_fuzz_bytes(tmp_path, data, k):
    """Random bytes (often not UTF-8): a Record or an InputError."""
    p = tmp_path / "fuzz.bin"
    p.write_bytes(data)
    _check_contract(p, FUZZ_FORMATS[k])


@settings(max_examples=200, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=st.lists(st.tuples(st.floats(width=32), st.floats(width=32)), max_size=12),
       t0=st.floats(-1e5, 1e5), sep=st.sampled_from([",", ";", "\t", " "]),
       header=st.booleans(), mutate=st.integers(0, 400),
       junk=st.sampled_from(["", "", ",", "x", " ", "\n", "1e", "-", "nan", "#"]))
def test_fuzz_near_valid_files(tmp_path, rows, t0, sep, header, mutate, junk):
    """Nearly valid files (uniform time, random numbers, one random insertion): Record or
    InputError."""
    lines = [sep.join(["time", "a", "b"])] if header else []
    lines += [sep.join(map(repr, [t0 + 0.01 * k, *map(float, r)])) for k, r in enumerate(rows)]
    text = "\n".join(lines)
    at = mutate % (len(text) + 1)
    p = tmp_path / "near.csv"
    p.write_text(text[:at] + junk + text[at:])
    _check_contract(p, FUZZ_FORMATS[0])


# --- sensors without a position ------------------------------------------------------------

def test_sensor_position_is_optional():
    """Old calls unchanged; a position-less sensor needs a name; axle detectors."""
    s = Sensor(x=6.0, y=4.0)
    assert (s.x, s.y, s.name, s.has_position) == (6.0, 4.0, "strain_x@6,4", True)
    assert Sensor(x=6.0).y == 0.0 and Sensor(x=6.0).name == "strain_x@6,0"
    s = Sensor(name="s01", kind="strain_x")
    assert (s.x, s.y, s.has_position) == (None, None, False)
    assert Sensor(y=2.0, name="g").has_position is False
    ad = Sensor(name="ad1", kind="axle_detector")
    assert ad.kind is SensorKind.AXLE_DETECTOR and not ad.kind.is_strain
    assert ad.kind.unit == "-" and SensorKind.STRAIN_Y.is_strain
    with pytest.raises(InputError,
                       match=re.escape("a strain_x sensor without a position (x) needs a name")):
        Sensor(kind="strain_x")
    with pytest.raises(InputError, match=re.escape("Sensor.y must be finite")):
        Sensor(name="a", y=float("inf"))


def test_fe_entry_points_refuse_sensors_without_position():
    """sensor_matrix (static, influence, simulate, calibration all go through it)."""
    bridge = bwim.Bridge.plate(length=8.0, width=6.0, nx=4, ny=3, thickness=0.4, E_x=30e9,
                               E_y=30e9, mu=1000.0)
    placed = Sensor(x=4.0, y=3.0)
    load = [bwim.PointLoad(x=4.0, y=3.0, P=1e4)]
    for bad, why in ((Sensor(name="s01"), "sensor 's01' has no position (x, y); an FE model "
                      "needs one"),
                     (Sensor(name="s02", y=3.0), "sensor 's02' has no position"),
                     (Sensor(x=4.0, y=3.0, name="ad1", kind="axle_detector"),
                      "sensor 'ad1' is an axle detector")):
        for call in (lambda s: bridge.static(load, [placed, s]),
                     lambda s: bridge.influence([s]),
                     lambda s: bridge.model.sensor_row(s)):
            with pytest.raises(InputError, match=re.escape(why)):
                call(bad)
    from bwim.dynamics import simulate
    from bwim.vehicles import two_axle_truck

    with pytest.raises(InputError, match="sensor 's01' has no position"):
        simulate(bridge, two_axle_truck(), speed=20.0, lane=3.0, sensors=[Sensor(name="s01")])


def test_positionless_sensors_round_trip_hdf5_and_sum(tmp_path, rng):
    """HDF5 stores an unknown position as NaN and reads None back; channels='sum' adds
    gauges that all lack x, and refuses a mix."""
    t, d = known(rng)
    p = tmp_path / "e.csv"
    p.write_text(text_of(t, d))
    r = read_logger(p, fmt(), sensors=[Sensor(name="s01", y=1.5)])
    io.write_record(r, tmp_path / "r.h5")
    q = io.read_record(tmp_path / "r.h5")
    assert [(s.name, s.x, s.y, s.kind) for s in q.sensors] == \
        [(s.name, s.x, s.y, s.kind) for s in r.sensors]
    assert np.array_equal(q.data, r.data) and np.array_equal(q.time, r.time)
    (ch,) = resolve_channels(r.sensors, "sum")
    assert ch.name == "s01+s02"
    with pytest.raises(InputError, match="cannot tell the section of gauge 's02'"):
        resolve_channels([Sensor(x=4.0, y=1.0, name="s01"), Sensor(name="s02")], "sum")


@pytest.mark.parametrize(("rate", "decimals"), [(100.0, 2), (1000.0, 3), (100.0, 3)])
def test_a_dropped_sample_of_a_clock_written_to_its_step(tmp_path, rate, decimals):
    """100 Hz written to 2 decimals steps exactly 0.01 s: one row missing is a step of
    0.02 s, a dropped sample (review of stop 33: the allowance of one unit of the last
    decimal, 0.01 s, let it through, and everything after it was one sample off); the
    same file whole is read, and so is a sampling_rate that agrees with it, not one that
    does not (50 Hz declared 100)."""
    n = 2000
    t = np.arange(n) / rate
    lines = [f"{t[k]:.{decimals}f},{np.sin(k / 10):.4f}\n" for k in range(n)]
    whole = tmp_path / "whole.txt"
    whole.write_text("".join(lines))
    f = LoggerFormat(columns=("time", "s01"))
    assert read_logger(whole, f).time.size == n
    dropped = tmp_path / "dropped.txt"
    dropped.write_text("".join(lines[:1000] + lines[1001:]))
    with pytest.raises(InputError, match=r"line 1001: .*a dropped sample"):
        read_logger(dropped, f)
    with pytest.raises(InputError, match="but sampling_rate is"):
        read_logger(whole, LoggerFormat(columns=("time", "s01"), sampling_rate=rate / 2))


def test_a_dot_between_digits_in_a_decimal_comma_file_is_refused(tmp_path):
    """decimal = ",": '1.234' is 1234 written with a thousands separator there, not 1.234
    (review of stop 33: read as 1.234 silently); refused with that hint, on the
    vectorised path and line by line alike."""
    p = tmp_path / "c.csv"
    f = LoggerFormat(columns=("time", "s01"), decimal=",")
    rows = "".join(f"{k / 100:.2f};{(k % 7) / 4:.2f}\n".replace(".", ",") for k in range(200))
    p.write_text(rows.replace("0,50\n", "1.234\n", 1))
    with pytest.raises(InputError, match=r"'1\.234' is not a number \(a '\.' with decimal "
                                         r"= ',': a thousands separator\?\)"):
        read_logger(p, f)
    p.write_text(rows)
    assert read_logger(p, f).time.size == 200


def test_a_header_of_numbers_and_a_first_row_of_nan(tmp_path):
    """Header detection (review of stop 33): channels named by numbers ('101;102') are a
    header when they are the columns' own names (they were read as the first sample);
    a first row of NaN (a sensor warming up) is data, refused as NaN (it was taken for a
    header and dropped: every sample one step early)."""
    p = tmp_path / "h.csv"
    p.write_text("101;102\n" + "".join(f"{k};{k * 2}\n" for k in range(10)))
    r = read_logger(p, LoggerFormat(columns=("101", "102"), sampling_rate=100.0))
    assert r.data[0].tolist() == [0.0, 0.0] and r.time.size == 10
    p.write_text("NaN;NaN\n" + "".join(f"{k};{k * 2}\n" for k in range(10)))
    with pytest.raises(InputError, match=r"line 1 .*column 'a': NaN sample"):
        read_logger(p, LoggerFormat(columns=("a", "b"), sampling_rate=100.0))
