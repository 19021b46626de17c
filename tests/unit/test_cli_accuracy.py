"""`bwim accuracy`: COST 323 classes from a weigh summary and a reference, on the CLI."""

import numpy as np
import pytest
from scipy import stats

from bwim.accuracy import confidence_level, min_confidence
from bwim.cli import main

HEADER = "record,n_axles,speed_m_s,axle_spacings_m,axle_weights_kN,gvw_kN,flags\n"


def _files(tmp_path, errors_pct):
    ref = ["record,n_axles,axle_spacings_m,axle_weights_kN,gvw_kN"]
    summ = [HEADER.strip()]
    for i, e in enumerate(errors_pct):
        w = np.array([60.0, 100.0 + i])
        ref.append(f"ev{i:03d}.txt,2,5.5,{w[0]:.3f};{w[1]:.3f},{w.sum():.3f}")
        m = w * (1 + e / 100)
        summ.append(f"ev{i:03d}.txt,2,20.0,5.5,{m[0]:.4f};{m[1]:.4f},{m.sum():.4f},")
    (tmp_path / "ref.csv").write_text("\n".join(ref) + "\n")
    (tmp_path / "summary.csv").write_text("\n".join(summ) + "\n")
    return tmp_path / "summary.csv", tmp_path / "ref.csv"


def test_accuracy_command_prints_the_class(tmp_path, capsys):
    """Errors with sd 2 % and no bias on 40 vehicles: gross weight in A(5) by the
    specification's test (checked here from the formula, not from the tool)."""
    errors = stats.norm.ppf((np.arange(40) + 0.5) / 40) * 2.0
    s, r = _files(tmp_path, errors)
    n, m, sd = 40, errors.mean(), errors.std(ddof=1)
    assert confidence_level(5.0, m, sd, n) >= min_confidence(n, "RR2", "I")
    out = tmp_path / "acc.csv"
    assert main(["accuracy", str(s), "--reference", str(r), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "Gross weight" in text or "gross" in text.lower()
    gross = next(line for line in out.read_text().splitlines()[1:]
                 if "gross" in line.lower())
    assert ",A(5)," in gross


def test_accuracy_bad_reference_is_one_line(tmp_path, capsys):
    s, r = _files(tmp_path, [0.0] * 5)
    r.write_text("record,axle_weights_kN\nx,1\n")  # no gross weight column
    assert main(["accuracy", str(s), "--reference", str(r)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("bwim: error:") and "\n" not in err


def test_accuracy_strict_names_unknown_records(tmp_path, capsys):
    s, r = _files(tmp_path, [0.5, -0.5, 0.2, 0.1, -0.3, 0.0])
    r.write_text(r.read_text() + "ghost.txt,2,5.5,60;100,160\n")
    assert main(["accuracy", str(s), "--reference", str(r), "--strict"]) == 2
    assert "ghost.txt" in capsys.readouterr().err
    assert main(["accuracy", str(s), "--reference", str(r)]) == 0


@pytest.mark.parametrize("bad", [["--repeatability", "r3"], ["--environment", "IV"]])
def test_accuracy_rejects_unknown_conditions(tmp_path, bad):
    s, r = _files(tmp_path, [0.0] * 5)
    with pytest.raises(SystemExit) as exc:
        main(["accuracy", str(s), "--reference", str(r), *bad])
    assert exc.value.code == 2


@pytest.mark.parametrize("name", ["taken.csv", "acc.txt"])
def test_the_output_is_checked_before_the_work(tmp_path, capsys, name):
    """An existing output or a suffix it cannot write is refused before anything is
    printed (docs/cli.md: outputs are checked before the work starts; review of stop 34:
    the whole table came first, then the refusal)."""
    s, r = _files(tmp_path, [0.0] * 5)
    (tmp_path / "taken.csv").write_text("mine\n")
    assert main(["accuracy", str(s), "--reference", str(r), "-o", str(tmp_path / name)]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and name in captured.err
    assert (tmp_path / "taken.csv").read_text() == "mine\n"
