"""The warm worker pool: its workers leave Ctrl-C to the parent and run the caller's warm-up
first."""

import os
import signal

from amr_twin.base import process_pool


def _sigint_handler() -> str:
    return "ignored" if signal.getsignal(signal.SIGINT) == signal.SIG_IGN else "handled"


def _mark_warm() -> None:
    os.environ["AMR_TWIN_TEST_WARM"] = str(os.getpid())


def _warm_mark() -> tuple[int, str | None]:
    return os.getpid(), os.environ.get("AMR_TWIN_TEST_WARM")


def test_a_pool_worker_leaves_ctrl_c_to_its_parent():
    """The terminal sends Ctrl-C to every process of the command: a worker that took it printed its
    KeyboardInterrupt traceback ("Process SpawnProcess-1: ..."); the parent stops the workers."""
    worker = process_pool._shared_pool(1).submit(_sigint_handler).result(timeout=120)
    assert worker == "ignored" and _sigint_handler() == "handled"


def test_a_worker_runs_the_callers_warm_up_before_its_first_item():
    pool = process_pool.worker_pool(1, _mark_warm)
    try:
        pid, mark = pool.submit(_warm_mark).result(timeout=120)
    finally:
        pool.shutdown()
    assert pid != os.getpid() and mark == str(pid)
