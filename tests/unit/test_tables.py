"""The presentation layer (bwim.tables): text and HTML tables, kN and % formats, parameter
walks.  References: the layout rules of the module's contract, written out by hand."""

import numpy as np

from bwim.tables import Table, format_kn, format_kn_each, format_pct, param_values, pct_change


def test_render_right_aligns_columns_under_title_and_rule():
    t = Table("Weights:", ("record", "GVW (kN)"), [("a.h5", 168.1), ("long.h5", "9.0")])
    assert t.render() == ("Weights:\n"
                          " record  GVW (kN)\n"
                          "-----------------\n"
                          "   a.h5     168.1\n"
                          "long.h5       9.0")
    # cells are held as text; no title line when the title is empty; short rows padded
    assert t.rows[0] == ("a.h5", "168.1")
    assert Table("", ("a", "bb"), [("1",)]).render() == "a  bb\n-----\n1    "


def test_html_escapes_every_cell_and_the_caption():
    page = Table("x < y", ("a&b",), [("<i>",)]).to_html()
    assert page == ("<table><caption>x &lt; y</caption><thead><tr><th>a&amp;b</th></tr>"
                    "</thead><tbody><tr><td>&lt;i&gt;</td></tr></tbody></table>")
    assert "<caption>" not in Table("", ("a",)).to_html()


def test_number_formats():
    assert format_kn(59.5e3) == "59.5" and format_kn(108.649e3, 2) == "108.65"
    assert format_kn_each(np.array([59.5e3, 108.6e3])) == ["59.5", "108.6"]
    assert format_kn_each(1e3) == ["1.0"]
    assert format_pct(0.8, 1.0) == "-20.00" and format_pct(3.0, 2.0, 1) == "+50.0"
    assert isinstance(pct_change(2.0, 1.0), float)
    np.testing.assert_allclose(pct_change([1.0, 3.0], [2.0, 2.0]), [-50.0, 50.0])


def test_param_values_labels_zones_and_missing_companions():
    params = {"E_x": np.array([1.0, 2.0]), "mu": np.array([5.0])}
    start = {"E_x": np.array([0.5, 1.5]), "mu": 4.0}
    rows = list(param_values(params, start, None, {"mu": [6.0]}))
    assert rows == [("E_x[0]", 1.0, 0.5, None, None), ("E_x[1]", 2.0, 1.5, None, None),
                    ("mu", 5.0, 4.0, None, 6.0)]
