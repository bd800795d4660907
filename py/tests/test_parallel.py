"""The GIL is released while the library computes.

1. While a simulation or a fit runs on one Python thread, another thread keeps running
   Python code (a native call holding the GIL would stop it until it returns).
2. Two fits, each on one thread of the search (threads=1), on two Python threads finish
   faster than one after the other. On two cores, two CPU-bound fits in parallel take about
   half the sequential time when the GIL is released and the whole of it when it is held
   (the threads would take turns): the bound 0.8 x sequential lies between those, with room
   for a second core that is not wholly free (CI machines have two cores). The same ratio is
   measured first for a control that is known to release the GIL (hashlib's SHA-256 of large
   buffers, CPython releases the GIL for data over 2 KiB): when the control does not reach
   the bound either, the machine has no second core to give (other processes hold it) and
   the comparison is skipped with both figures, rather than failed.
"""

import hashlib
import os
import threading
import time

import pytest

import breathing_torso as bt

FIT = dict(lod=0, max_evals=20, threads=1, subject={"stature": 1.75, "mass": 75}, as_frame=False)
BOUND = 0.8


def ratio_of(work):
    """Wall time of work(0) and work(1) on two threads over their time one after the other,
    with the seconds of each."""
    t0 = time.perf_counter()
    work(0)
    work(1)
    sequential = time.perf_counter() - t0
    threads = [threading.Thread(target=work, args=(k,)) for k in range(2)]
    t0 = time.perf_counter()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    parallel = time.perf_counter() - t0
    return parallel / sequential, sequential, parallel


def keeps_running_python(call):
    """Wakings of this thread, every millisecond, while `call` runs on another, and the
    seconds it ran (each waking needs the GIL back)."""
    done = threading.Event()
    failed = []

    def work():
        try:
            call()
        except BaseException as e:  # reported on this thread
            failed.append(e)
        finally:
            done.set()

    worker = threading.Thread(target=work, daemon=True)
    n = 0
    t0 = time.perf_counter()
    worker.start()
    while not done.wait(0.001):
        n += 1
    seconds = time.perf_counter() - t0
    worker.join()
    if failed:
        raise failed[0]
    return n, seconds


def test_python_runs_while_the_library_computes(synth_recording):
    """A 60 s simulation and a fit on a worker thread leave this thread running Python: it
    wakes every millisecond, so it wakes at least 100 times a second of their run (some
    wakings are lost to the scheduler on a loaded machine). A call holding the GIL would
    leave it none until the call returned."""
    sim, sim_s = keeps_running_python(lambda: bt.Torso(lod=0).simulate(60.0, outputs=["volume.lung"], rate=10))
    fit, fit_s = keeps_running_python(lambda: bt.fit(synth_recording, **{**FIT, "max_evals": 10}))
    print(f"wakings while the library computed: simulation {sim} in {sim_s:.2f} s, fit {fit} in {fit_s:.2f} s")
    assert sim > 100 * sim_s and fit > 100 * fit_s


def test_two_fits_on_two_threads_run_in_parallel(synth_recording):
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    if (cores or 1) < 2:
        pytest.skip(f"{cores} core: nothing to run in parallel on")
    bt.fit(synth_recording, **FIT)  # warm the page cache and the allocator
    data = os.urandom(1 << 24)
    control, cs, cp = ratio_of(lambda k: [hashlib.sha256(data).digest() for _ in range(60)])
    results = [None, None]

    def fit(k):
        results[k] = bt.fit(synth_recording, **FIT)["cost_m"]

    ratio, sequential, parallel = ratio_of(fit)
    print(f"two fits: sequential {sequential:.2f} s, on two threads {parallel:.2f} s, ratio {ratio:.2f}; "
          f"control (SHA-256): {cs:.2f} s, {cp:.2f} s, ratio {control:.2f}")
    assert results[0] == results[1], "the same fit gives the same result on any thread"
    if control >= BOUND:
        pytest.skip(f"no second core free: the GIL-free control ran at {control:.2f} x sequential on "
                    f"two threads (the fits at {ratio:.2f} x)")
    assert ratio < BOUND, f"two threads took {ratio:.2f} x the sequential time: the GIL is held"
