"""The HTML report (bwim.report) and the record plot (bwim.plots.records)."""

from __future__ import annotations

import pytest

from bwim import paper
from bwim.dynamics.crossing import simulate
from bwim.errors import InputError
from bwim.io import write_record
from bwim.mfi import identify_forces
from bwim.plots.records import plot_record
from bwim.report import Table, read_results, render_html, section, write_report
from bwim.scenario import save_bridge


@pytest.fixture(scope="module")
def record():
    return simulate(paper.slab_bridge(), paper.truck(), speed=paper.SPEED, lane=paper.LANE,
                    sensors=paper.sensors(), approach=5.0, sampling_rate=400.0)


def test_plot_record_draws_every_channel(record):
    fig = plot_record(record, length=12.0, title="crossing")
    ax = fig.axes[0]
    assert len(ax.lines) == len(record.sensors)
    assert ax.get_ylabel() == "strain (µε)" and ax.get_title() == "crossing"
    two = plot_record(record, channels=["x6_2", "x6_4"])
    assert len(two.axes[0].lines) == 2


def test_sections_and_page(record):
    strain_x = [s for s in record.sensors if s.kind.value == "strain_x"]
    ident = identify_forces(paper.slab_bridge(), record.channels(strain_x))
    sections = [section(ident, "truck", truth=record.truth),
                section(record, "crossing", length=12.0),
                section(paper.slab_bridge(), "true bridge"),
                section(Table("numbers", ("a", "b"), (("1", "2"),)))]
    assert "error (%)" in sections[0].tables[0].rows[2][0]
    page = render_html("A <report>", sections, intro="intro & more")
    assert "<title>A &lt;report&gt;</title>" in page and "intro &amp; more" in page
    assert page.count("data:image/png;base64,") == 3  # forces, L-curve, record
    assert "Moving force identification: truck" in page and "E_x" in page
    with pytest.raises(InputError, match="cannot report"):
        section(42)


def test_read_results_and_atomic_write(record, tmp_path):
    write_record(record, tmp_path / "rec.h5")
    save_bridge(paper.slab_bridge(), tmp_path / "bridge.toml")
    (tmp_path / "summary.csv").write_text("record,gvw_kN\nrec.h5,168.1\n")
    items = read_results([tmp_path])
    assert [n for n, _ in items] == ["bridge.toml", "rec.h5", "summary.csv"]
    out = write_report(tmp_path / "r.html", [section(o, n) for n, o in items])
    assert out.read_text(encoding="utf-8").count("<table>") >= 3
    with pytest.raises(InputError, match="no such file"):
        read_results([tmp_path / "missing.h5"])
    (tmp_path / "bad.h5").write_text("no")
    with pytest.raises(InputError, match=r"bad\.h5"):
        read_results([tmp_path / "bad.h5"])
    with pytest.raises(InputError, match="does not exist"):
        write_report(tmp_path / "no" / "r.html", [])
    assert not (tmp_path / "no").exists()
