"""The operator's site report (bwim.report.site): figures, tables, notes, overloads, flags.

The summaries here are made by hand (rows with chosen times, lanes, classes, weights and
flags), not by the weighing code, so every expected count follows from the construction.
"""

from __future__ import annotations

import re
from datetime import datetime, time, timedelta
from html import escape
from pathlib import Path

import numpy as np
import pytest

from bwim.accuracy import ReferenceRow, assess
from bwim.errors import InputError
from bwim.plots.traffic import hourly_counts
from bwim.report import OverloadLimits, TrafficSummary, render_html, site_sections
from bwim.report.flags import FLAG_TABLE, explain, flag_meanings
from bwim.report.overloads import overloads
from bwim.report.runs import CalibrationRun, CalibrationRuns, is_runs_table, read_calibration_runs
from bwim.report.site import reference_pairs
from bwim.summary import SummaryRow

ROOT = Path(__file__).resolve().parents[2]
KN = 1000.0
T0 = datetime(2015, 10, 1, 8, 0, 0)
#: Axle spacings (m) of each class's silhouette.
SPACINGS = {"11": (4.5,), "12": (4.2, 1.3), "113": (3.6, 6.0, 1.3, 1.3)}

TRAFFIC_FIGURES = ("Gross vehicle weight histogram", "Axle-load spectrum",
                   "Speed distribution", "Vehicles by class", "Vehicles by lane",
                   "Flow per hour")
ACCURACY_FIGURES = ("Weighed against static gross weight", "Gross weight error histogram")
RUN_FIGURES = ("Calibration runs: scale factor over the day",
               "Calibration runs: residual of each run")


def _day(n: int = 30) -> tuple[list[SummaryRow], list[ReferenceRow], np.ndarray]:
    """n vehicles 7 minutes apart from 08:00 in lanes 1 and 2, classes in turn; every
    fifth refused (two on the bridge), every seventh weighed with a soft flag; the
    reference holds every third weighed vehicle with a chosen gross error (%)."""
    rng = np.random.default_rng(7)
    rows, refs, errors = [], [], []
    for k in range(n):
        cls = list(SPACINGS)[k % 3]
        sp = SPACINGS[cls]
        common = dict(record=f"ev{k:03d}.csv", time=T0 + timedelta(minutes=7 * k),
                      lane=1 + k % 2, direction="+x", vehicle_class=cls, n_axles=len(sp) + 1,
                      speed=20.0 + k % 5, axle_spacings=sp, lateral=2.0 + 0.1 * k,
                      lateral_unit="gauge index")
        if k % 5 == 4:
            rows.append(SummaryRow(**common, flags=("multiple_presence",),
                                   reason="two vehicles on the bridge"))
            continue
        w = rng.uniform(40.0, 90.0, len(sp) + 1) * KN
        soft = ("ill_conditioned",) if k % 7 == 0 else ()
        rows.append(SummaryRow(**common, axle_weights=w, gvw=float(w.sum()), flags=soft,
                               quality="warning" if soft else "ok", method="moses"))
        if k % 3 == 0:
            e = [-3.0, 1.0, 2.5, -0.5, 4.0][len(errors) % 5]
            errors.append(e)
            refs.append(ReferenceRow(record=f"ev{k:03d}.csv", gvw=float(w.sum()) / (1 + e / 100),
                                     axle_weights=w / (1 + e / 100), axle_spacings=sp))
    rows.append(SummaryRow(record="broken.csv", status="failed", reason="cannot read"))
    return rows, refs, np.array(errors)


def _runs(times: bool = True) -> CalibrationRuns:
    return CalibrationRuns(name="calibration_runs.csv", runs=tuple(
        CalibrationRun(name=f"run{k}.csv", speed=15.0, lateral=3.0 + k, scale=1.0 + 0.01 * k,
                       residual=0.03, status="used" if k != 2 else "residual outlier",
                       time=T0 + timedelta(hours=k) if times else None)
        for k in range(5)))


def _images(page: str) -> list[str]:
    """The alt texts (captions) of the page's embedded PNG figures."""
    return re.findall(r'<img alt="([^"]*)" src="data:image/png;base64,[A-Za-z0-9+/=]+">',
                      page)


def test_site_report_has_every_figure_and_the_tables():
    rows, refs, _ = _day()
    page = render_html("site", site_sections(TrafficSummary(name="summary.csv", rows=rows),
                                             reference=refs, runs=_runs()))
    assert sorted(_images(page)) == sorted(TRAFFIC_FIGURES + ACCURACY_FIGURES + RUN_FIGURES)
    assert page.count("<figure id=") == 10
    # the per-vehicle table sits in the scrolling box, one row per summary row + header
    box = re.search(r'<div class="scroll"><table><caption>Every vehicle.*?</table></div>',
                    page, re.S)
    assert box is not None and box.group(0).count("<tr>") == len(rows) + 1
    assert "lateral (gauge index)" in box.group(0) and "lateral (m" not in box.group(0)
    # the summary table counts what the construction made: 30 seen, 24 weighed, 6 refused
    summary = re.search(r"<caption>Summary</caption>.*?</table>", page, re.S).group(0)
    assert re.search(r"vehicles seen</td><td[^>]*>30<", summary)
    assert re.search(r"weighed</td><td[^>]*>24 \(80 %\)<", summary)
    assert re.search(r"failed records[^<]*</td><td[^>]*>1<", summary)
    # flags in words, with the document's text (docs/flags.md)
    assert escape(flag_meanings()["multiple_presence"].meaning) in page
    assert escape(flag_meanings()["ill_conditioned"].meaning) in page


def test_counts_by_class_and_lane_count_vehicles_not_failed_records():
    """30 vehicles in classes 11, 12, 113 in turn (10 each) and lanes 1, 2 (15 each); the
    failed record is no vehicle."""
    from bwim.plots.traffic import plot_counts

    rows = _day()[0]
    for by, keys, each in (("class", ["11", "12", "113"], 10), ("lane", ["1", "2"], 15)):
        ax = plot_counts(rows, by=by).axes[0]
        assert [t.get_text() for t in ax.get_xticklabels()] == keys
        weighed, other = ax.containers
        totals = [a.get_height() + b.get_height() for a, b in zip(weighed, other, strict=True)]
        assert totals == [each] * len(keys)


def test_missing_columns_leave_figures_out_with_a_note():
    """A summary with no time, lane, class or speed (the contract's columns only), no
    reference and no runs: the weight figures only, and a note for each one left out."""
    rows = [SummaryRow(record=f"e{k}.csv", n_axles=2, axle_spacings=(4.0,),
                       axle_weights=(50e3, 60e3 + k * KN), gvw=110e3 + k * KN)
            for k in range(6)]
    page = render_html("bare", site_sections(TrafficSummary(name="s.csv", rows=rows)))
    assert sorted(_images(page)) == ["Axle-load spectrum", "Gross vehicle weight histogram"]
    for note in ("No time column: the flow per hour is left out",
                 "No lane column", "No class column", "No speed in the summary",
                 "No static reference given", "No calibration runs table given"):
        assert note in page, note
    nothing = [SummaryRow(record="e.csv", reason="no axles", flags=("no_axles",))]
    page = render_html("none", site_sections(TrafficSummary(name="s.csv", rows=nothing)))
    assert _images(page) == [] and "No vehicle was weighed" in page
    empty = render_html("empty", site_sections(TrafficSummary(name="s.csv", rows=()),
                                               reference=[ReferenceRow(record="a", gvw=1e5)]))
    assert _images(empty) == [] and "No reference vehicle was weighed" in empty


def test_hourly_counts_follow_the_clock():
    """Vehicles at 08:05, 08:40, 08:59 (one refused), none at 09, 10:01 and 10:30: every
    hour between the first and the last, the empty one included."""
    def row(h, m, weighed=True):
        kw = dict(axle_weights=(50e3, 50e3), gvw=100e3) if weighed else {}
        return SummaryRow(record=f"r{h}{m}.csv", time=datetime(2015, 10, 1, h, m), **kw)

    rows = [row(8, 5), row(8, 40), row(8, 59, False), row(10, 1), row(10, 30),
            SummaryRow(record="x.csv", status="failed", reason="x")]
    labels, weighed, other = hourly_counts(rows)
    assert labels == ["08:00", "09:00", "10:00"]
    assert weighed.tolist() == [2, 0, 2] and other.tolist() == [1, 0, 0]
    # clock times of day only, and a row without a time (left out)
    rows = [SummaryRow(record="a.csv", time=time(23, 10)), SummaryRow(record="b.csv"),
            SummaryRow(record="c.csv", time=time(21, 0))]
    labels, weighed, other = hourly_counts(rows)
    assert labels == ["21:00", "22:00", "23:00"] and other.tolist() == [1, 0, 1]
    # ... across midnight: from 23:50 to 00:20 is two hours, not the day's 24 (review of
    # stop 33: 00:00-23:00 with 22 empty hours between)
    rows = [SummaryRow(record=f"{k}.csv", time=t)
            for k, t in enumerate((time(23, 50), time(0, 10), time(0, 20)))]
    labels, weighed, other = hourly_counts(rows)
    assert labels == ["23:00", "00:00"] and other.tolist() == [1, 2]
    # several dates: labels carry the date
    rows = [row(23, 30), SummaryRow(record="n.csv", time=datetime(2015, 10, 2, 0, 15))]
    assert hourly_counts(rows)[0] == ["2015-10-01 23:00", "2015-10-02 00:00"]


def test_overloads_are_strict_and_configurable():
    limits = OverloadLimits(gvw=400e3, axle=100e3)
    at = SummaryRow(record="at.csv", axle_weights=(100e3, 100e3, 100e3, 100e3),
                    gvw=400e3)  # exactly at both limits: not an overload
    over_gvw = SummaryRow(record="g.csv", axle_weights=(90e3,) * 5, gvw=450e3)
    over_axle = SummaryRow(record="a.csv", axle_weights=(60e3, 110e3), gvw=170e3)
    refused = SummaryRow(record="r.csv", reason="two vehicles")
    found = overloads([at, over_gvw, over_axle, refused], limits)
    assert [(o.row.record, o.what) for o in found] == [("g.csv", ("gvw",)),
                                                       ("a.csv", ("axle",))]
    assert found[0].excess_pct == pytest.approx(12.5) and found[1].excess_pct == \
        pytest.approx(10.0)
    assert overloads([over_gvw], OverloadLimits(gvw=None, axle=100e3)) == ()
    # the defaults: the EU's 40 t gross and 11.5 t axle (Directive 96/53/EC) times 9.81
    assert OverloadLimits().gvw == pytest.approx(392.4e3)
    assert OverloadLimits().axle == pytest.approx(112.815e3)
    for bad in (0.0, -1.0, float("nan"), "heavy"):
        with pytest.raises(InputError, match="gvw"):
            OverloadLimits(gvw=bad)


def test_reference_pairs_give_the_injected_errors_and_agree_with_assess():
    """The scatter's pairs: their gross errors are the ones put into the reference, and
    their mean and std are those of bwim.accuracy.assess's gross-weight criterion (an
    independent matching)."""
    rows, refs, injected = _day()
    pairs = reference_pairs(rows, refs)
    errors = np.array([100 * (w.gvw - r.gvw) / r.gvw for w, r in pairs])
    np.testing.assert_allclose(errors, injected, atol=1e-9)
    gross = assess(rows, refs).criterion("gross_weight")
    assert gross.n == len(pairs)
    assert gross.mean == pytest.approx(errors.mean(), abs=1e-12)
    assert gross.std == pytest.approx(errors.std(ddof=1), abs=1e-12)
    # a reference naming a refused vehicle makes no pair
    refused = next(r for r in rows if r.status == "refused")
    assert reference_pairs(rows, [ReferenceRow(record=refused.record, gvw=1e5)]) == ()
    # two vehicles in one record: the reference's vehicle number, else its lane, decides
    two = [SummaryRow(record="e.csv", vehicle=1, lane=1, axle_weights=(50e3, 50e3),
                      gvw=100e3),
           SummaryRow(record="e.csv", vehicle=2, lane=2, axle_weights=(60e3, 60e3),
                      gvw=120e3)]
    for ref, gvw in ((ReferenceRow(record="e.csv", gvw=1e5, lane=2), 120e3),
                     (ReferenceRow(record="e.csv", gvw=1e5, vehicle=1, lane=2), 100e3)):
        (pair,) = reference_pairs(two, [ref])
        assert pair[0].gvw == gvw
        assert assess(two, [ref, ReferenceRow(record="x.csv", gvw=1e5)]).n_vehicles == 1


def _doc_rows() -> list[tuple[tuple[str, ...], str, str]]:
    text = (ROOT / "docs" / "flags.md").read_text(encoding="utf-8")
    out = []
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if not line.startswith("| `"):
            continue
        flags = tuple(re.findall(r"`([a-z_]+)`", cells[0]))
        out.append((flags, cells[1].replace("`", ""), cells[2].replace("`", "")
                    if len(cells) > 2 else ""))
    return out


def test_flag_vocabulary_is_the_documents_word_for_word():
    """report.flags.FLAG_TABLE holds docs/flags.md's flag tables, in order (no drift
    between the page's explanations and the document).  The table may be ahead of this
    branch's document by rows that are on main (issue 20's temperature flags)."""
    doc = _doc_rows()
    table = [(f, m, look) for _, f, m, look in FLAG_TABLE]
    assert [row for row in table if row[0] in {d[0] for d in doc}] == doc
    groups = {g for g, *_ in FLAG_TABLE}
    assert groups == {"hard", "soft", "detection"}
    assert explain("gvw_high").look_at == explain("axle_weight_high").look_at  # "as above"
    assert explain("made_up").group == "unknown"


def test_runs_table_is_read_back(tmp_path):
    p = tmp_path / "calibration_runs.csv"
    p.write_text("run,speed (m/s),lateral,scale,residual,status,time\n"
                 "r1.csv,14.20,3.10,1.0100,0.031,used,2015-10-01T07:30:00\n"
                 "r2.csv,,,,,detection failed,\n")
    assert is_runs_table(p)
    runs = read_calibration_runs(p)
    assert [r.name for r in runs.runs] == ["r1.csv", "r2.csv"] and runs.n_used == 1
    assert runs.runs[0].scale == 1.01 and runs.runs[0].time == datetime(2015, 10, 1, 7, 30)
    assert runs.runs[1].scale is None and not runs.runs[1].used
    assert runs.runs[0].lateral == 3.1
    # the lateral column names its unit (review of stop 37), read as the plain one
    for unit in ("m", "gauge index"):
        p.write_text(f"run,speed (m/s),lateral ({unit}),scale,residual,status\n"
                     "r1.csv,14.20,3.10,1.0100,0.031,used\n")
        assert read_calibration_runs(p).runs[0].lateral == 3.1
    p.write_text("run,speed (m/s),lateral,scale,residual,status\nr1.csv,14,3,big,0.03,used\n")
    with pytest.raises(InputError, match=r"line 2: column scale: 'big'"):
        read_calibration_runs(p)
    (tmp_path / "s.csv").write_text("record,n_axles\n")
    assert not is_runs_table(tmp_path / "s.csv")


def test_runs_without_times_are_drawn_in_order_with_a_note():
    from bwim.plots.runs import plot_run_scales

    page = render_html("r", site_sections(TrafficSummary(name="s.csv", rows=_day(10)[0]),
                                          runs=_runs(times=False)))
    assert escape("drawn in the table's order") in page
    fig = plot_run_scales(_runs(times=True))
    assert fig.axes[0].get_xlabel() == "clock time (h)"
    used = fig.axes[0].lines[0].get_xydata()
    np.testing.assert_allclose(used[:, 0], [8, 9, 11, 12])  # 08:00 + k h, run 2 left out


def test_report_command_writes_the_site_report_and_refuses_to_overwrite(tmp_path, capsys):
    from bwim.cli import main
    from bwim.io.summary import write_summary

    rows, refs, _ = _day()
    write_summary(tmp_path / "summary.csv", rows)
    (tmp_path / "ref.csv").write_text("record,gvw_kN\n" + "".join(
        f"{r.record},{r.gvw / KN:.4f}\n" for r in refs))
    (tmp_path / "calibration_runs.csv").write_text(
        "run,speed (m/s),lateral,scale,residual,status\n"
        + "".join(f"r{k}.csv,15.0,3.0,{1 + k / 100:.4f},0.03,used\n" for k in range(4)))
    out = tmp_path / "report.html"
    argv = ["report", str(tmp_path / "summary.csv"), str(tmp_path / "calibration_runs.csv"),
            "--reference", str(tmp_path / "ref.csv"), "-o", str(out)]
    assert main(argv) == 0
    page = out.read_text(encoding="utf-8")
    assert sorted(_images(page)) == sorted(TRAFFIC_FIGURES + ACCURACY_FIGURES + RUN_FIGURES)
    assert f"COST 323 accuracy of {tmp_path.name}/summary.csv against ref.csv" in page
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "exists; use --force" in err
    assert out.read_text(encoding="utf-8") == page
    assert main([*argv, "--force"]) == 0
    assert main(["report", str(tmp_path / "calibration_runs.csv"), "--reference",
                 str(tmp_path / "ref.csv"), "-o", str(tmp_path / "r2.html")]) == 2
    assert "needs a weigh summary.csv" in capsys.readouterr().err


def test_two_results_summaries_get_two_titles(tmp_path):
    """``bwim report results/ static/``: each summary's section is named with its folder
    (review of stop 34: both were "Site summary: summary.csv")."""
    from bwim.cli import main
    from bwim.io.summary import write_summary

    rows, _, _ = _day()
    for folder in ("mfi", "lines"):
        (tmp_path / folder).mkdir()
        write_summary(tmp_path / folder / "summary.csv", rows)
    out = tmp_path / "two.html"
    assert main(["report", str(tmp_path / "mfi" / "summary.csv"),
                 str(tmp_path / "lines" / "summary.csv"), "-o", str(out)]) == 0
    page = out.read_text(encoding="utf-8")
    assert "Site summary: mfi/summary.csv" in page and "Site summary: lines/summary.csv" in page
