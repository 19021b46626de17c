"""Summary rows (bwim.summary, bwim.io.summary): one schema for every command, and no
refused or doubtful weight ever written as a weight.

References: the schema's own contract (a row that is not weighed carries no weight);
round trips through the CSV file; moving forces on a simply supported beam (weights that
the exact model returns, for the algebra of the row) made implausible on purpose.
"""

import dataclasses
from datetime import datetime, time

import numpy as np
import pytest

import bwim
from bwim.accuracy import ReferenceRow, assess
from bwim.detect import VehicleDetection
from bwim.errors import InputError
from bwim.io.summary import COLUMNS, CONTRACT_COLUMNS, read_summary, write_summary
from bwim.site import EventWeighing
from bwim.summary import SummaryRow, failed_row


def test_a_row_that_is_not_weighed_carries_no_weight():
    with pytest.raises(InputError, match="carries no weights"):
        SummaryRow(record="a", status="refused", gvw=300e3, reason="x")
    with pytest.raises(InputError, match="carries no weights"):
        SummaryRow(record="a", status="failed", axle_weights=(1.0, 2.0), reason="x")
    with pytest.raises(InputError, match="reject"):
        SummaryRow(record="a", gvw=300e3, quality="reject")
    with pytest.raises(InputError, match="needs its gross weight"):
        SummaryRow(record="a", status="weighed")
    with pytest.raises(InputError, match="needs its reason"):
        SummaryRow(record="a", status="failed")
    assert SummaryRow(record="a").reason == "not weighed"
    assert failed_row("a.txt", "unreadable").status == "failed"
    # review of stop 33: what the CSV reader refuses, the schema refuses too
    with pytest.raises(InputError, match="weights are positive"):
        SummaryRow(record="a", status="weighed", gvw=-5e3, axle_weights=(-5e3,))
    with pytest.raises(InputError, match="weights are positive"):
        SummaryRow(record="a", gvw=300e3, axle_weights=(310e3, -10e3))
    with pytest.raises(InputError, match="flags must be a sequence of flags"):
        SummaryRow(record="a", flags="multiple_presence")
    with pytest.raises(InputError, match="1 axle_spacings for n_axles = 3"):
        SummaryRow(record="a", n_axles=3, axle_spacings=(4.0,))
    with pytest.raises(InputError, match="3 axle_weights for n_axles = 2"):
        SummaryRow(record="a", gvw=3e5, n_axles=2, axle_weights=(1e5,) * 3)


def test_the_file_has_one_column_list_and_round_trips(tmp_path):
    rows = [
        SummaryRow(record="e1.txt", time=datetime(2026, 5, 14, 9, 45, 52, 576000), lane=1,
                   direction="+x", vehicle_class="113", n_axles=5, speed=23.456,
                   axle_spacings=(3.8, 6.0, 1.3, 1.3),
                   axle_weights=(61.61e3, 108.5e3, 90.84e3, 69.85e3, 70.63e3),
                   gvw=401.43e3, group_weights=(61.61e3, 108.5e3, 231.32e3),
                   flags=("ill_conditioned",), lateral=5.213, lateral_unit="m",
                   group_laterals=(5.102, 5.331, 5.2), confidence=0.95,
                   residual=0.0312, quality="warning", method="moses",
                   drift_factor=0.9734, drift_method="trend"),
        SummaryRow(record="e1.txt", vehicle=2, status="refused", time=time(15, 0, 1, 500000),
                   lane=3, direction="-x", n_axles=2, speed=20.0, axle_spacings=(4.0,),
                   flags=("multiple_presence",), reason="multiple presence"),
        failed_row("e2.txt", "e2.txt: line 40: 17 fields, expected 19"),
    ]
    path = tmp_path / "summary.csv"
    write_summary(path, rows)
    header = path.read_text().splitlines()[0].split(",")
    assert tuple(header) == COLUMNS and tuple(header[:7]) == CONTRACT_COLUMNS
    back = read_summary(path)
    assert [r.key for r in back] == [r.key for r in rows]
    assert back[0].time == rows[0].time and back[1].time == rows[1].time
    for a, b in zip(back, rows, strict=True):
        for f in dataclasses.fields(SummaryRow):
            x, y = getattr(a, f.name), getattr(b, f.name)
            if isinstance(y, float) or (isinstance(y, tuple) and y and
                                        isinstance(y[0], float)):
                np.testing.assert_allclose(x, y, rtol=1e-4)
            else:
                assert x == y, f.name


def test_a_file_with_a_weight_on_a_refused_row_is_refused(tmp_path):
    path = tmp_path / "summary.csv"
    path.write_text("record,n_axles,axle_spacings_m,axle_weights_kN,gvw_kN,status,reason\n"
                    "a,2,4.0,50;60,110,refused,two vehicles\n")
    with pytest.raises(InputError, match=r"line 2.*carries no weights"):
        read_summary(path)


def _beam_identification():
    """Moving forces on a 20 m beam identified with the same model (the algebra only)."""
    beam = bwim.Bridge.beam(length=20.0, n_elements=20, E=3.5e10, I=1.0, mu=15000.0,
                            z_bottom=0.8)
    sensors = [bwim.Sensor(x=x, kind="strain_x") for x in (5.0, 10.0, 15.0)]
    forces = bwim.MovingForces(axle_loads=[80e3, 120e3], axle_spacings=[4.0])
    rec = bwim.simulate(beam, forces, speed=20.0, sensors=sensors, sampling_rate=200.0,
                        approach=0.0, tail=0.2)
    return bwim.identify_forces(beam, rec, lam=1e-2)


def test_identification_rows_refuse_implausible_weights():
    ident = _beam_identification()
    [row] = ident.to_summary_rows("beam.h5")
    assert row.weighed and row.method == "mfi" and row.vehicle_class == "11"
    np.testing.assert_allclose(row.gvw, 200e3, rtol=0.02)
    bad = dataclasses.replace(ident, axle_weights=-ident.axle_weights)
    [row] = bad.to_summary_rows("beam.h5")
    assert row.status == "refused" and row.quality == "reject"
    assert row.gvw is None and row.axle_weights == () and "negative" in row.reason


def test_a_tensile_identified_force_refuses_the_vehicle():
    """``negative_force`` is a hard flag (docs/flags.md): an identification with an
    axle's force 20 kN tensile where it is weighed (as an under-regularised one gives)
    is refused, not written with its weights (it was: quality 'warning')."""
    ident = _beam_identification()
    f = ident.axle_forces.copy()
    inside = np.flatnonzero((ident.time >= ident.axle_windows[0, 0])
                            & (ident.time <= ident.axle_windows[0, 1]))
    f[inside[inside.size // 2], 0] = -20e3
    [row] = dataclasses.replace(ident, axle_forces=f).to_summary_rows("beam.h5")
    assert row.status == "refused" and row.quality == "reject" and row.gvw is None
    assert "negative_force" in row.flags


@pytest.mark.parametrize("flag", ["negative_force", "open_at_end", "split_across_records",
                                  "residual_high"])
def test_a_weighed_row_cannot_carry_a_hard_flag(flag):
    """The schema itself refuses a weight beside a hard flag, whatever its quality says."""
    with pytest.raises(InputError, match=f"hard flags: {flag}"):
        SummaryRow(record="a", gvw=300e3, quality="warning", flags=(flag,))


def test_static_weights_rows_refuse_a_rejected_weighing():
    ident = _beam_identification()
    passage = ident.passages[0]
    w = bwim.StaticWeights(axle_weights=np.array([80e3, 120e3]), time=np.zeros(1),
                           measured=np.zeros((1, 1)), fitted=np.zeros((1, 1)), channels=(),
                           passage=passage, residual=0.9, condition=1.0, groups=((0,), (1,)),
                           flags=("residual_high",), quality="reject")
    row = w.to_summary_row("r.h5")
    assert row.status == "refused" and row.gvw is None and not row.group_weights
    assert "residual_high" in row.reason
    ok = dataclasses.replace(w, flags=(), quality="ok").to_summary_row("r.h5")
    assert ok.weighed and ok.gvw == pytest.approx(200e3)


def _vehicle(speed=20.0, spacings=(4.0,), lane=5.0):
    p = bwim.Passage(speed=speed, lane=lane, axle_spacings=np.array(spacings), delay=0.5)
    return VehicleDetection(passage=p, confidence=0.9, lateral=lane, lateral_unit="m")


def test_event_rows_one_per_vehicle_none_with_weights_unless_weighed():
    from bwim.site import VehicleWeighing

    a, b = _vehicle(), _vehicle(spacings=(3.5, 1.3))
    why = "multiple presence: 2 vehicles on the bridge, not weighed as one"
    ev = EventWeighing(weighed=False, reason=why, clock=datetime(2026, 5, 14, 9, 0, 0),
                       vehicles=tuple(VehicleWeighing(vehicle=v, lane=1, direction="+x",
                                                      weighed=False, reason=why,
                                                      flags=("multiple_presence",))
                                      for v in (a, b)))
    rows = ev.to_summary_rows("e.txt")
    assert [r.vehicle for r in rows] == [1, 2]
    assert all(r.status == "refused" and r.gvw is None for r in rows)
    assert [r.vehicle_class for r in rows] == ["11", "12"]
    assert rows[0].time == datetime(2026, 5, 14, 9, 0, 0, 500000)
    assert rows[0].lane == 1 and rows[0].direction == "+x"
    assert ev.to_summary_row("e.txt") == rows[0]
    nothing = EventWeighing(weighed=False, reason="detection failed: no channel 'ad1'")
    [row] = nothing.to_summary_rows("e.txt")
    assert row.status == "refused" and "ad1" in row.reason


def test_assess_takes_rows_without_a_file_and_matches_vehicles():
    """Two rows of one record (the weighed lane-1 truck and a refused lane-3 vehicle): the
    reference picks its vehicle by lane; a reference row's vehicle number wins."""
    rows = [SummaryRow(record=f"e{k}", lane=1, gvw=(400 + k) * 1e3) for k in range(6)]
    rows.append(SummaryRow(record="e0", vehicle=2, lane=3, reason="multiple presence"))
    ref = [ReferenceRow(record=f"e{k}", gvw=400e3, lane=1) for k in range(6)]
    result = assess(rows, ref)
    assert result.n_vehicles == 6 and not result.missing and result.n_unreferenced == 1
    by_vehicle = assess(rows, [*ref[1:], ReferenceRow(record="e0", gvw=400e3, vehicle=2)])
    assert by_vehicle.missing == ("e0#2",)
    with pytest.raises(InputError, match="twice"):
        assess([*rows, rows[0]], ref)


def test_a_weighed_row_refused_keeps_all_but_its_weights():
    """SummaryRow.refused: no weight left, the flags added once after the row's own,
    quality reject, the reason given; the rest (record, time, lane, speed...) kept."""
    from datetime import datetime

    from bwim.summary import SummaryRow

    row = SummaryRow(record="e.txt", vehicle=2, time=datetime(2026, 7, 20, 9, 0), lane=1,
                     direction="+x", n_axles=2, speed=22.0, axle_weights=(60e3, 90e3),
                     group_weights=(60e3, 90e3), gvw=150e3, flags=("gauge_fault:s12",),
                     quality="warning", method="moses", lateral=5.9, lateral_unit="m")
    out = row.refused("another vehicle", "unconfirmed_gauge_fault", "gauge_fault:s12")
    assert out.status == "refused" and not out.weighed and out.gvw is None
    assert out.axle_weights == () and out.group_weights == ()
    assert out.flags == ("gauge_fault:s12", "unconfirmed_gauge_fault")
    assert out.quality == "reject" and out.reason == "another vehicle"
    assert (out.key, out.time, out.lane, out.speed, out.lateral) == (
        row.key, row.time, row.lane, row.speed, row.lateral)
