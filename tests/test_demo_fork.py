"""The demo forks its workers only beside threads known to be safe (``app/demo.py``).

A fork copies the calling thread alone; a lock another thread holds stays held in the
child. The demo forks its twin workers while its drawing pool runs (that pool's manager and
queue feeder threads take only that pool's locks): "fork" then, and "forkserver" beside any
other thread. Checked in a fresh interpreter with one BLAS thread (as the command line
sets it), whose threads the test knows.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

CHECK = """
import threading
from concurrent.futures import ProcessPoolExecutor
from wirecal.app.demo import _start_method, _workers

print(_start_method())                         # the interpreter alone
with _workers(1) as drawer:                    # a pool with its threads running
    print(_start_method((drawer,)))            # beside it, as the demo forks its twin pool
    print(_start_method())                     # the same threads, not known
    with _workers(1, (drawer,)) as pool:       # the twin pool: forked beside the drawer
        print(pool._mp_context.get_start_method())
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()                              # a thread of someone else's
    print(_start_method((drawer,)))
    stop.set()
    other.join()
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="fork is the rule on Linux")
def test_workers_fork_only_beside_the_demos_own_threads():
    one_blas_thread = {
        v: "1" for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
    }
    env = {**os.environ, **one_blas_thread}  # as the command line sets them: no BLAS pool
    out = subprocess.run(
        [sys.executable, "-c", CHECK],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
        env=env,
    )
    assert out.stdout.split() == ["fork", "fork", "forkserver", "fork", "forkserver"]
