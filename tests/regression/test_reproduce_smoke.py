"""Fast smoke versions of the paper's §5.1 and §5.4 reproductions (the full runs are
``make reproduce``): the report's numbers meet PAPER_CASES' targets."""

import numpy as np

from bwim.cli import main
from bwim.paper.reproduce import case_5_1


def test_reproduce_5_1_quick():
    report = case_5_1(quick=True)
    errors = report.numbers["errors"]
    # PAPER_CASES §5.1: each parameter within 1 %; calibrated MFI weights within 2 % and
    # force RMS within 5 % over the central 80 %
    assert max(abs(v) for v in errors.values()) < 1.0
    assert np.all(np.abs(report.numbers["mfi_weight_error"]) < 0.02)
    assert np.all(np.array(report.numbers["mfi_rms_error"]) < 0.05)
    text = report.render()
    assert "paper" in text and "-0.60" in text  # the paper's number beside ours


def test_reproduce_5_4_quick_from_the_command_line(tmp_path, capsys):
    assert main(["reproduce", "5.4", "--quick", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "Table 2" in out and "34.8" in out  # the paper's girder E beside ours
    assert (tmp_path / "5_4_mfi_forces.png").stat().st_size > 10_000
