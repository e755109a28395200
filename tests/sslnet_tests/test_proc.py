"""sslnet.proc: the per-thread CPU reader the benches use."""

from __future__ import annotations

import os
import threading
import time

import pytest

from sslnet.proc import process_cpu_s, thread_cpu_s


def test_thread_cpu_counts_a_busy_thread_and_knows_the_main_thread() -> None:
    stop = threading.Event()
    started = threading.Event()
    tid: list[int] = []

    def burn() -> None:
        tid.append(threading.get_native_id())
        started.set()
        x = 0
        while not stop.is_set():
            x += 1

    t = threading.Thread(target=burn, daemon=True)
    t.start()
    assert started.wait(5.0)
    try:
        before = thread_cpu_s(os.getpid())
        deadline = time.monotonic() + 10.0  # bounded: the busy thread needs one tick of CPU
        after = before
        while time.monotonic() < deadline:
            after = thread_cpu_s(os.getpid())
            key = next(k for k in after if k[1] == tid[0])
            if after[key] > before.get(key, 0.0):
                break
            stop.wait(0.01)
        keys = {k[1]: k for k in after}
        assert os.getpid() in keys  # the main thread's id is the process id
        busy = keys[tid[0]]
        assert after[busy] > before.get(busy, 0.0)
        assert all(v >= 0.0 for v in after.values())
    finally:
        stop.set()
        t.join(5.0)


def test_thread_cpu_of_a_process_that_does_not_exist_is_empty() -> None:
    assert thread_cpu_s(2**22 + 12345) == {}


def test_process_cpu_holds_its_threads_and_refuses_a_missing_process() -> None:
    threads = sum(thread_cpu_s(os.getpid()).values())
    process = process_cpu_s(os.getpid())  # read after: it can only have grown
    assert process > 0.0  # this test process has run
    # the process counts its live threads and those that ended (other tests' threads)
    assert process >= threads - 0.011
    with pytest.raises(OSError):
        process_cpu_s(2**22 + 12345)
