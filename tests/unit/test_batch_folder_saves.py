"""A batch's periodic saves and its day-level steps (review of stop 33): with a
``finalize`` (the day-level checks of bwim weigh on logger files), a periodic save writes
the manifest only, so that summary.csv never holds rows the day has not judged (a
killed run left a weight the day refuses); the final save writes the judged rows.
Reference: the rows the test gives and what its finalize does to them."""

from __future__ import annotations

import pytest

from bwim.batch import BatchFolder, Item, run_into
from bwim.batch.events import Outcome
from bwim.io.outputs import MANIFEST_NAME
from bwim.io.summary import read_summary
from bwim.summary import SummaryRow


def _outcome(k: int, name: str) -> Outcome:
    return Outcome(index=k, name=name,
                   rows=(SummaryRow(record=name, gvw=300e3, axle_weights=(100e3, 200e3)),))


def _refuse_all(rows):
    return [r.refused("the day refuses it", "lateral_outlier") for r in rows]


@pytest.mark.parametrize("finalize", [None, _refuse_all])
def test_periodic_saves_write_no_unjudged_rows(tmp_path, finalize):
    src = []
    for k in range(3):
        p = tmp_path / f"r{k}.txt"
        p.write_text(str(k))
        src.append(p)
    out = tmp_path / "out"
    out.mkdir()
    folder = BatchFolder(out, meta={}, resume=False, force=False, finalize=finalize)
    folder.save_every = 0.0
    seen = []

    def run(todo):
        for k, it in enumerate(todo):
            if k == 2:  # after two periodic saves: what is on disk now
                seen.append((out / "summary.csv").exists())
                assert (out / MANIFEST_NAME).exists()
            yield _outcome(k, it.name)

    run_into(folder, [Item(name=p.name, source=p) for p in src], run)
    assert seen == [finalize is None]
    rows = read_summary(out / "summary.csv")
    assert len(rows) == 3
    assert all(r.weighed for r in rows) == (finalize is None)


def test_an_interrupted_day_level_step_writes_no_summary(tmp_path):
    """Ctrl-C while the day's steps run: the summary is not written (the rows were not
    judged); the manifest keeps the work for --resume."""
    p = tmp_path / "r.txt"
    p.write_text("x")
    out = tmp_path / "out"
    out.mkdir()

    def interrupted(rows):
        raise KeyboardInterrupt

    folder = BatchFolder(out, meta={}, resume=False, force=False, finalize=interrupted)
    with pytest.raises(KeyboardInterrupt):
        run_into(folder, [Item(name=p.name, source=p)], lambda todo: iter([_outcome(0, p.name)]))
    assert not (out / "summary.csv").exists() and (out / MANIFEST_NAME).exists()


def test_a_record_name_of_another_file_is_refused(tmp_path):
    """run_into refuses an input named as another file's rows in the folder (the
    summary would hold two rows of one record), before processing anything."""
    from bwim.errors import InputError

    a, b = tmp_path / "a" / "r.txt", tmp_path / "b" / "r.txt"
    for p in (a, b):
        p.parent.mkdir()
        p.write_text("x")
    out = tmp_path / "out"
    out.mkdir()
    folder = BatchFolder(out, meta={}, resume=False, force=False)
    run_into(folder, [Item(name="r.txt", source=a)], lambda todo: iter([_outcome(0, "r.txt")]))
    again = BatchFolder(out, meta={}, resume=True, force=False)
    with pytest.raises(InputError, match=r"already holds record 'r\.txt' from"):
        run_into(again, [Item(name="r.txt", source=b)], lambda todo: iter(()))
    same = BatchFolder(out, meta={}, resume=True, force=False)  # the same file: a resume
    assert run_into(same, [Item(name="r.txt", source=a)], lambda todo: iter(())
                    ).n_done_before == 1
