"""``bwim weigh --bridge`` with a site model file: a model that is not accepted is refused
with a one-line error before anything is weighed or written (issue 23: never weigh with
a model that cannot weigh its own calibration truck).  Data: the session's small site."""

import pytest

from bwim.cli import main
from bwim.scenario import build_bridge, load_scenario, save_site_model
from bwim.site import SiteModel


def test_weigh_refuses_a_model_that_is_not_accepted(small_site, tmp_path, capsys):
    bridge = build_bridge(load_scenario(small_site.scenario))
    path = tmp_path / "model.toml"
    save_site_model(SiteModel(bridge=bridge, gains={"s01": 1e6}, accepted=False,
                              reason="it weighs its own calibration run 2 at +14.0 %"), path)
    out = tmp_path / "out"
    code = main(["weigh", str(small_site.scenario), str(small_site.out_dir / "traffic"),
                 "--calibration-records", str(small_site.out_dir / "calibration"),
                 "--bridge", str(path), "-o", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code != 0 and not (out / "summary.csv").exists()
    assert len(err) == 1 and "not accepted" in err[0] and "+14.0 %" in err[0]


@pytest.mark.parametrize(("option", "value", "named"), [
    ("--mesh-correction", "fine", "mesh_correction"),  # not a number of bisections
    ("--mass", "free", "--mass"),  # the paper calibration's; the logger fit has its own
])
def test_calibrate_refuses_a_bad_option_in_one_line(small_site, tmp_path, capsys, option,
                                                     value, named):
    """``bwim calibrate SITE calibration/ --mesh-correction fine`` (a bad value) and
    ``--mass free`` (the site's logger fit takes the mass from the free vibration
    itself): exit 2, one line naming the option, no model written."""
    out = tmp_path / "model.toml"
    code = main(["calibrate", str(small_site.scenario), str(small_site.out_dir / "calibration"),
                 "-o", str(out), option, value])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and named in err[0]
    assert not out.exists()


def test_calibrate_refuses_to_save_the_model_among_its_runs(small_site, tmp_path, capsys):
    """``bwim calibrate SITE cal/ -o cal/site-model.toml`` (review of stop 37): a logger's
    records folder takes any file, so the model would be read as a calibration run next
    time, and the model then refused as made from other runs.  Refused in one line before
    any work, nothing written."""
    import shutil

    cal = tmp_path / "calibration"
    shutil.copytree(small_site.out_dir / "calibration", cal)
    before = sorted(p.name for p in cal.iterdir())
    code = main(["calibrate", str(small_site.scenario), str(cal), "-o",
                 str(cal / "site-model.toml")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "is the input folder" in err[0], err
    assert sorted(p.name for p in cal.iterdir()) == before
