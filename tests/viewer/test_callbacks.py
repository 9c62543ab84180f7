"""The viewer's callback gate: errors reported, calls serialised, nothing after close."""

import threading
import time

from orientviz.viewer.callbacks import CallbackGate


def test_an_exception_becomes_a_message():
    said = []
    gate = CallbackGate(said.append)
    gate.wrap(lambda: 1 / 0)()
    assert said == ["ZeroDivisionError: division by zero"]


def test_a_skipped_call_and_a_call_after_close_do_nothing():
    runs, syncing = [], [True]
    gate = CallbackGate(print)
    cb = gate.wrap(lambda: runs.append(1), skip=lambda: syncing[0])
    cb()
    syncing[0] = False
    cb()
    gate.close()
    cb()
    assert runs == [1] and gate.closed


def test_close_waits_for_a_callback_still_running():
    started, order = threading.Event(), []

    def slow():
        started.set()
        time.sleep(0.2)
        order.append("callback")

    gate = CallbackGate(print)
    t = threading.Thread(target=gate.wrap(slow))
    t.start()
    assert started.wait(5)
    gate.close()
    order.append("closed")
    t.join()
    assert order == ["callback", "closed"]
