"""``bwim weigh`` says why the traffic's own drift reference was not used and what it
needs (a thin traffic date, as on the real installation of issue 20, must not fall back
to the time of day silently).  Data: the session's small site (four traffic events, no
calibration-date traffic in the batch)."""

from bwim.cli import main


def test_weigh_says_what_the_traffic_drift_needed(small_site, tmp_path, capsys):
    code = main(["weigh", str(small_site.scenario), str(small_site.out_dir / "traffic"),
                 "--calibration-records", str(small_site.out_dir / "calibration"),
                 "-o", str(tmp_path / "out")])
    out = capsys.readouterr().out
    assert code in (0, 1), out
    lines = out.splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("drift:"))
    assert "time of day" in lines[k]
    assert lines[k + 1].startswith("note: the traffic's own reference was not used: it "
                                   "needs the steering axle's nominal load")
    assert "[drift] reference_kN" in lines[k + 1]
