"""Units and legends of the report's figures (bwim.plots.wim, bwim.plots.records).

Lines and records are made by hand with known ordinates, so the plotted values follow by
unit conversion alone: µε per kN = (strain per N) × 1e3 × 1e6; logger units per kN =
(reading per N) × 1e3.
"""

from __future__ import annotations

import numpy as np
import pytest

from bwim.plots.records import plot_record
from bwim.plots.wim import plot_influence_line
from bwim.records import Record
from bwim.sensors import Sensor
from bwim.wim import InfluenceLine
from bwim.wim.influence_line import Channel

X = np.linspace(0.0, 10.0, 21)
SHAPE = np.sin(np.pi * X / 10.0)  # zero at both ends, as a line must be


def _line(peak_per_n: float, n: int = 2, source: str = "matrix method",
          lane: float = 4.81) -> InfluenceLine:
    channels = tuple(Channel.of([Sensor(name=f"g{k + 1}", kind="strain_x")])
                     for k in range(n))
    ordinates = np.outer(SHAPE, peak_per_n * (1.0 + 0.1 * np.arange(n)))
    return InfluenceLine(x=X, ordinates=ordinates, channels=channels, lane=lane,
                         source=source)


def test_uncalibrated_line_is_labelled_reading_units_not_microstrain():
    """A logger line of 1.75e-4 units per N (0.175 per kN, which the issue saw drawn as
    175 000 "µε per kN") against a strain line of 1e-9 per N (1 µε per kN)."""
    ax = plot_influence_line(_line(1.75e-4)).axes[0]
    assert "reading units per kN" in ax.get_ylabel() and "µε" not in ax.get_ylabel()
    assert ax.lines[0].get_ydata().max() == pytest.approx(0.175)
    ax = plot_influence_line(_line(1e-9)).axes[0]
    assert "µε per kN" in ax.get_ylabel()
    assert ax.lines[0].get_ydata().max() == pytest.approx(1.0)
    forced = plot_influence_line(_line(1e-9), units="reading").axes[0]
    assert forced.lines[0].get_ydata().max() == pytest.approx(1e-6)
    with pytest.raises(ValueError, match="units"):
        plot_influence_line(_line(1e-9), units="furlongs")


def test_lateral_position_gets_a_unit_only_when_known():
    assert plot_influence_line(_line(1e-9)).axes[0].get_title().startswith(
        "Influence line, lateral position 4.81,")
    title = plot_influence_line(_line(1e-9), lateral_unit="gauge index").axes[0].get_title()
    assert "lateral 4.81 (gauge index)" in title and " m," not in title
    fe = _line(1e-9, source="FE model", lane=3.5)
    assert "lane 3.5 m" in plot_influence_line(fe).axes[0].get_title()


def _right_of_axes(fig, artist) -> bool:
    fig.canvas.draw()
    box = artist.get_window_extent()
    return box.x0 >= fig.axes[0].get_window_extent().x1


def test_legends_do_not_cover_the_curves():
    """Two channels: the legend stands beside the axes.  Fourteen (the issue's case): a
    colour bar tells them apart and every curve is drawn."""
    fig = plot_influence_line(_line(1e-9), reference=_line(1.1e-9, source="FE model"))
    assert _right_of_axes(fig, fig.axes[0].get_legend())
    fig = plot_influence_line(_line(1e-9, n=14), reference=_line(1e-9, n=14,
                                                                 source="FE model"))
    ax = fig.axes[0]
    assert len(ax.lines) == 2 * 14 + 1 and len(fig.axes) == 2  # the axes and a colour bar
    assert len(ax.get_legend().get_texts()) == 2  # line styles only
    assert fig.axes[1].get_ylabel() == "channel (order in the line)"


def test_record_in_logger_units_and_many_channels():
    t = np.linspace(0.0, 1.0, 50)
    sensors = tuple(Sensor(name=f"ch{k:02d}", kind="strain_x") for k in range(16))
    counts = np.outer(np.sin(np.pi * t), 3000.0 + np.arange(16))  # logger counts
    fig = plot_record(Record(time=t, data=counts, sensors=sensors))
    ax = fig.axes[0]
    assert ax.get_ylabel() == "reading (logger units)"
    assert ax.lines[0].get_ydata().max() == pytest.approx(3000.0, rel=1e-3)
    bar = fig.axes[1]
    assert bar.get_ylabel() == "channel" and "ch00" in [x.get_text() for x in
                                                         bar.get_yticklabels()]
    strain = Record(time=t, data=counts[:, :2] * 1e-8, sensors=sensors[:2])
    fig = plot_record(strain)
    assert fig.axes[0].get_ylabel() == "strain (µε)"
    assert _right_of_axes(fig, fig.axes[0].get_legend())
