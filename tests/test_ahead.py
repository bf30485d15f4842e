"""cablecheck.run.ahead: states made on a worker thread come out in order, errors and
early closes reach the consumer, a set-up runs on the worker first, the
worker's CPU time is counted (the set-up's apart), the queue is sized by the
states' bytes and the interpreter's switch interval is put back."""

from __future__ import annotations

import sys
import threading
import time

import pytest
from hypothesis import given, settings, strategies as st
from helpers import busy_states

from cablecheck.run.ahead import AHEAD_BYTES, DEPTH, MAX_DEPTH, SWITCH_INTERVAL, StepsAhead, depth_for


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
    ahead = StepsAhead(busy_states(3, 0.02), depth=1)   # 20 ms of the worker's CPU per state
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


def test_before_runs_on_the_worker_first_and_its_cpu_is_kept_apart():
    seen = []

    def settle():
        seen.append(("before", threading.current_thread().name))
        t = time.thread_time()
        while time.thread_time() - t < 0.03:      # 30 ms of the worker's CPU, before any state
            pass

    def states():
        seen.append(("first", threading.current_thread().name))
        yield from range(3)

    with StepsAhead(states(), before=settle) as ahead:
        assert list(ahead) == [0, 1, 2]
    worker = "cablecheck-simulation"
    assert seen == [("before", worker), ("first", worker)]
    assert 0.03 <= ahead.before_cpu < 0.2 and ahead.cpu < 0.03


def test_an_error_before_the_states_reaches_the_consumer():
    def settle():
        raise RuntimeError("the model is unstable")

    made = []
    ahead = StepsAhead((made.append(k) or k for k in range(3)), before=settle)
    with pytest.raises(RuntimeError, match="unstable"):
        list(ahead)
    ahead.close()
    assert made == []                              # no state is made after a failed set-up


@pytest.mark.parametrize("state_bytes, depth", [(1, MAX_DEPTH), (AHEAD_BYTES // 1000, 1000),
                                                (AHEAD_BYTES, DEPTH), (0, MAX_DEPTH)])
def test_the_queue_holds_about_ahead_bytes_of_states_within_its_bounds(state_bytes, depth):
    assert depth_for(state_bytes) == depth
