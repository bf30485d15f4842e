"""The stop request (cablecheck.run.stop): the first SIGINT or SIGTERM only sets the
flag, a second raises KeyboardInterrupt, leaving puts the old handlers back,
and outside the main thread nothing is replaced."""

from __future__ import annotations

import signal
import threading

import pytest

from cablecheck.run.stop import StopRequest


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_first_signal_is_a_flag_the_second_interrupts(sig):
    before = {s: signal.getsignal(s) for s in StopRequest.SIGNALS}
    with StopRequest() as stop:
        assert not stop.asked and stop.signal_name is None
        signal.raise_signal(sig)
        assert stop.asked and stop.signal_name == sig.name
        with pytest.raises(KeyboardInterrupt):
            signal.raise_signal(signal.SIGTERM)
        assert stop.signal_name == sig.name          # the first signal is the one named
    assert {s: signal.getsignal(s) for s in StopRequest.SIGNALS} == before


def test_outside_the_main_thread_the_handlers_are_left_alone():
    before = {s: signal.getsignal(s) for s in StopRequest.SIGNALS}
    seen = []

    def enter():
        with StopRequest() as stop:
            seen.append(({s: signal.getsignal(s) for s in StopRequest.SIGNALS}, stop.asked))

    worker = threading.Thread(target=enter)
    worker.start()
    worker.join()
    assert seen == [(before, False)]
