"""The terminal's step display (cassini_bayes.inference.progress): nothing at all unless shown."""

from __future__ import annotations

from cassini_bayes.inference import progress


def test_steps_are_silent_without_a_display(capsys):
    assert progress.active() is None
    with progress.step("preparing") as task:
        assert task is None
    with progress.shown(False), progress.step("sampling", total=10) as task:
        assert task is None and progress.active() is None
    out = capsys.readouterr()
    assert out.out == "" and out.err == ""


def test_shown_opens_one_display_and_nests(capsys):
    with progress.shown():
        outer = progress.active()
        assert outer is not None
        with progress.shown(), progress.step("inner", total=3) as task:
            assert progress.active() is outer and task is not None
            assert len(outer.tasks) == 1
        assert len(outer.tasks) == 0   # a finished step leaves the display
    assert progress.active() is None
