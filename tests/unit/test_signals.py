"""SIGTERM ends a command even when Python swallows the KeyboardInterrupt it raises (issue
22; seen in CI: the signal landed in a weak reference's callback, whose exceptions Python
only prints, and ``identify --jobs 2`` ran on to exit 0)."""

import gc
import os
import signal
import weakref

import pytest

from bwim.io.outputs import signals_as_interrupt


class _Thing:
    pass


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")  # by design
def test_a_signal_swallowed_in_a_weakref_callback_still_interrupts():
    def on_collect(_ref):
        os.kill(os.getpid(), signal.SIGTERM)  # handled here: the exception is swallowed

    reached_the_end = False
    with pytest.raises(KeyboardInterrupt, match="signal 15"):
        with signals_as_interrupt():
            thing = _Thing()
            ref = weakref.ref(thing, on_collect)
            del thing
            gc.collect()
            reached_the_end = ref() is None
    assert reached_the_end  # the block ran on: the interrupt came at its end


def test_a_signal_interrupts_at_once_otherwise():
    with pytest.raises(KeyboardInterrupt, match="signal 15"):
        with signals_as_interrupt():
            os.kill(os.getpid(), signal.SIGTERM)
            pytest.fail("the block went on after the signal")


def test_the_handlers_are_restored():
    before = signal.getsignal(signal.SIGTERM)
    with signals_as_interrupt():
        pass
    assert signal.getsignal(signal.SIGTERM) is before
