"""cablecheck.run.apart: states made in a forked child come out in order,
errors (with the child's traceback) and a dead child reach the consumer, a
set-up runs in the child first with its progress reported here, a stop
asked here ends the child, at most `depth` states are in flight, the child's
CPU time is counted (the set-up's apart), its last word comes back, and it
neither answers Ctrl-C nor writes this process's buffered output again."""

from __future__ import annotations

import multiprocessing
import os
import signal
import subprocess
import sys
import threading
import time

import pytest
from hypothesis import given, settings, strategies as st

from cablecheck.run.apart import StepsApart, available
from tests.helpers import busy_states, examples

pytestmark = pytest.mark.skipif(not available(), reason="no fork here: runs step ahead on a thread")


@settings(max_examples=examples(8), deadline=None)
@given(st.lists(st.integers(), max_size=60), st.integers(1, 6))
def test_states_come_out_in_order(items, depth):
    with StepsApart(iter(items), depth) as apart:
        assert list(apart) == items


def test_states_are_made_in_another_process():
    def pids():
        for _ in range(3):
            yield os.getpid()

    with StepsApart(pids(), 4) as apart:
        made = list(apart)
    assert len(made) == 3 and len(set(made)) == 1 and made[0] != os.getpid()


def test_an_error_comes_after_the_states_made_before_it_with_the_childs_traceback():
    def states():
        yield 1
        yield 2
        raise ValueError("unstable")

    apart = StepsApart(states(), 8)
    got = []
    with pytest.raises(ValueError, match="unstable") as caught:
        for s in apart:
            got.append(s)
    apart.close()
    assert got == [1, 2]
    assert any("in the simulation process" in note and "states" in note for note in caught.value.__notes__)


def test_an_error_that_cannot_be_pickled_is_named():
    class Local(Exception):      # a class pickle cannot find by name
        pass

    def states():
        yield 1
        raise Local("odd")

    apart = StepsApart(states(), 8)
    with pytest.raises(RuntimeError, match="Local: odd"):
        list(apart)
    apart.close()


def test_a_child_that_dies_ends_the_states_with_an_error_naming_it():
    def states():
        yield 1
        os.kill(os.getpid(), signal.SIGKILL)
        yield 2

    apart = StepsApart(states(), 8)
    with pytest.raises(RuntimeError, match=r"ended without a word \(exit status -9\)"):
        list(apart)
    apart.close()


def test_close_stops_the_child_early_and_at_most_depth_states_are_in_flight():
    made = multiprocessing.get_context("fork").Value("i", 0)

    def endless():
        while True:
            with made.get_lock():
                made.value += 1
            yield made.value

    apart = StepsApart(endless(), 4)
    it = iter(apart)
    assert [next(it) for _ in range(3)] == [1, 2, 3]
    time.sleep(0.2)                              # the child would run on if nothing held it
    assert made.value <= 3 + 4                   # the consumed and the depth
    apart.close()
    assert not apart._process.is_alive()
    assert list(it) == []


def test_a_stop_asked_here_ends_the_child_after_the_states_in_flight():
    taken = []

    def halted():
        return len(taken) >= 5

    apart = StepsApart(iter(range(1000)), 3, halted=halted)
    for s in apart:
        taken.append(s)
    apart.close()
    # the state being handed on when the stop is seen, and the depth's in flight
    assert taken == list(range(len(taken))) and 5 <= len(taken) <= 5 + 1 + 3


def test_a_stop_asked_while_the_child_sets_up_ends_it_at_once():
    """No state taken yet (the run still builds): the stop reaches the child
    settling all the same, which ends its set-up and makes no state."""
    asked_at = time.perf_counter() + 0.2

    def settle(report, halted):
        end = time.perf_counter() + 10.0
        while not halted() and time.perf_counter() < end:    # ten seconds of settling unless stopped
            time.sleep(0.005)

    apart = StepsApart(iter(range(3)), 8, before=settle, halted=lambda: time.perf_counter() > asked_at)
    time.sleep(0.5)                              # the run building: nothing taken
    start = time.perf_counter()
    assert list(apart) == []
    apart.close()
    assert time.perf_counter() - start < 1.0 and apart.before_cpu < 1.0


def test_child_cpu_is_counted_and_waiting_is_not():
    apart = StepsApart(busy_states(3, 0.02), 1)   # 20 ms of the child's CPU per state
    time.sleep(0.2)                               # the child waits for a slot meanwhile
    assert list(apart) == [0, 1, 2]
    apart.close()
    assert 0.06 <= apart.cpu < 0.2


def test_before_runs_in_the_child_first_its_progress_here_and_its_cpu_apart():
    seen = []

    def settle(report, halted):
        report("settle", 1, 2)
        assert not halted()
        t = time.thread_time()
        while time.thread_time() - t < 0.03:      # 30 ms of the child's CPU, before any state
            pass
        report("settle", 2, 2)

    def states():
        yield from range(3)

    def progress(*args):
        seen.append((args, threading.current_thread() is threading.main_thread()))

    with StepsApart(states(), 8, before=settle, progress=progress) as apart:
        assert list(apart) == [0, 1, 2]
    assert seen == [(("settle", 1, 2), False), (("settle", 2, 2), False)]
    assert 0.03 <= apart.before_cpu < 0.2 and apart.cpu < 0.03


def test_an_error_before_the_states_reaches_the_consumer():
    made = multiprocessing.get_context("fork").Value("i", 0)

    def settle(report, halted):
        raise RuntimeError("the model is unstable")

    def states():
        for k in range(3):
            made.value += 1
            yield k

    apart = StepsApart(states(), 8, before=settle)
    with pytest.raises(RuntimeError, match="unstable"):
        list(apart)
    apart.close()
    assert made.value == 0                       # no state is made after a failed set-up


def test_an_error_reporting_progress_ends_the_states_with_it():
    def settle(report, halted):
        report("settle", 1, 2)

    def progress(*args):
        raise OSError("the terminal is gone")

    apart = StepsApart(iter(range(3)), 8, before=settle, progress=progress)
    with pytest.raises(OSError, match="terminal is gone"):
        list(apart)
    apart.close()


def test_the_childs_last_word_comes_back():
    state = {"stepped": 0}

    def states():
        for k in range(4):
            state["stepped"] += 1               # the child's copy
            yield k

    with StepsApart(states(), 8, finish=lambda: dict(state)) as apart:
        assert list(apart) == [0, 1, 2, 3]
    assert apart.finished == {"stepped": 4} and state["stepped"] == 0


def test_the_child_ignores_ctrl_c():
    def states():
        yield 1
        os.kill(os.getpid(), signal.SIGINT)      # as Ctrl-C reaches the whole process group
        yield 2

    with StepsApart(states(), 8) as apart:
        assert list(apart) == [1, 2]


def test_the_child_does_not_write_this_process_buffered_output_again():
    code = ("import sys; sys.stdout.write('before'); "
            "from cablecheck.run.apart import StepsApart; "
            "a = StepsApart(iter(range(3)), 4); assert list(a) == [0, 1, 2]; a.close(); print('|after')")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out == "before|after\n"
