"""sim.ahead: states made on a worker thread come out in order, errors and
early closes reach the consumer, the worker's CPU time is counted and the
interpreter's switch interval is put back."""

from __future__ import annotations

import sys
import threading
import time

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sim.ahead import SWITCH_INTERVAL, StepsAhead


@settings(max_examples=25, deadline=None)
@given(st.lists(st.integers(), max_size=40), st.integers(1, 6))
def test_states_come_out_in_order(items, depth):
    with StepsAhead(iter(items), depth=depth) as ahead:
        assert list(ahead) == items


def test_an_error_comes_after_the_states_made_before_it():
    def states():
        yield 1
        yield 2
        raise ValueError("unstable")

    ahead = StepsAhead(states())
    got = []
    with pytest.raises(ValueError, match="unstable"):
        for s in ahead:
            got.append(s)
    ahead.close()
    assert got == [1, 2]


def test_close_stops_the_worker_early():
    made = []

    def endless():
        k = 0
        while True:
            made.append(k)
            yield k
            k += 1

    ahead = StepsAhead(endless(), depth=4)
    it = iter(ahead)
    assert [next(it) for _ in range(3)] == [0, 1, 2]
    ahead.close()
    assert not any(t.name == "cablecheck-simulation" and t.is_alive() for t in threading.enumerate())
    assert len(made) <= 3 + 4 + 2          # the consumed, the queue's depth, the one in hand
    assert list(it) == []


def test_worker_cpu_is_counted_and_waiting_is_not():
    def busy():
        for k in range(3):
            t = time.thread_time()
            while time.thread_time() - t < 0.02:   # 20 ms of the worker's CPU per state
                pass
            yield k

    ahead = StepsAhead(busy(), depth=1)
    time.sleep(0.2)                               # the worker waits on a full queue meanwhile
    assert list(ahead) == [0, 1, 2]
    ahead.close()
    assert 0.06 <= ahead.cpu < 0.2


def test_switch_interval_is_short_while_running_and_put_back():
    before = sys.getswitchinterval()
    ahead = StepsAhead(iter(range(3)))
    assert sys.getswitchinterval() == min(before, SWITCH_INTERVAL)
    list(ahead)
    ahead.close()
    assert sys.getswitchinterval() == before
