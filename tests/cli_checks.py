"""Checks shared by the command-line tests."""


def one_line_error(code, err, *needles):
    """The command failed as bad input does: exit code 2, one line ``bwim: error: ...`` on
    stderr, naming each of ``needles``."""
    assert code == 2, err
    assert err.startswith("bwim: error: ") and err.count("\n") == 1, err
    for n in needles:
        assert n in err, err
