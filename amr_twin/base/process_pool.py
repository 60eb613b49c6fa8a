"""A local pool of warm worker processes (used by
:func:`amr_twin.experiments.runner.executor.run_all`).

Workers are spawned (MuJoCo and its threads are never forked), die with their
parent even when it is killed outright, and run the caller's ``warm`` function as
they start (the twin's: :func:`amr_twin.recording.run.warm_up`), in parallel with the
caller's own work; a pool is kept for the life of the process, so
a second sweep or suite finds it warm. The calling process simulates too, taking the
next item whenever it is free, and a worker is handed an item only once it is warm
and idle: a worker that is slow to start never holds an item the caller could have
run, so ``jobs=2`` is never slower than ``jobs=1`` by more than the hand-over of one
result.
"""

from __future__ import annotations

import atexit
import multiprocessing
import os
from collections import deque
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any, Callable, Iterator

Warm = Callable[[], None] | None
"""A picklable module-level function a worker runs as it starts (imports), or None."""


def usable_cores() -> int:
    """CPU cores this process may run on (its affinity mask), >= 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


def check_jobs(jobs: int | None) -> int:
    """``--jobs``: None -> one worker per usable core; otherwise 1 .. usable cores, or ValueError.

    Each worker is a process of its own (about 170 MB with MuJoCo loaded) that keeps
    one core busy: more workers than cores only add memory and switching.
    """
    cores = usable_cores()
    if jobs is None:
        return cores
    if not 1 <= jobs <= cores:
        raise ValueError(
            f"--jobs {jobs}: must be in 1..{cores} on this machine ({cores} usable cores; each "
            "worker is a ~170 MB process simulating on one core, more only add memory)"
        )
    return jobs


def _warm_worker(parent_pid: int, warm: Warm) -> None:
    """Pool worker start-up: die with the parent, then run ``warm`` (the twin's imports: numpy,
    MuJoCo, the model build and the loop) before the first item arrives. Ctrl-C is the parent's
    to handle (it
    stops the workers): a worker ignores SIGINT, which the terminal sends to every process of the
    command (each printed its traceback)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _watch_parent(parent_pid)
    if warm is not None:
        warm()


def _ready() -> int:
    """A worker's first task: it is warm when this returns (its pid)."""
    return os.getpid()


def worker_pool(workers: int, warm: Warm = None) -> ProcessPoolExecutor:
    """A new pool of ``workers`` spawned, parent-death-guarded processes, each running ``warm``
    as it starts (the caller shuts it down); :func:`pool_results` keeps one per size and warm-up."""
    context = multiprocessing.get_context("spawn")
    return ProcessPoolExecutor(
        max_workers=workers,
        mp_context=context,
        initializer=_warm_worker,
        initargs=(os.getpid(), warm),
    )


_pools: dict[tuple[int, Warm], ProcessPoolExecutor] = {}


def _shared_pool(workers: int, warm: Warm = None) -> ProcessPoolExecutor:
    """The process' pool of ``workers`` workers warmed by ``warm``, made on first use."""
    pool = _pools.get((workers, warm))
    if pool is None or getattr(pool, "_broken", False) or getattr(pool, "_shutdown_thread", False):
        pool = _pools[(workers, warm)] = worker_pool(workers, warm)
        if len(_pools) == 1:
            atexit.register(_close_pools)
    return pool


def _close_pools() -> None:
    for pool in _pools.values():
        pool.shutdown(wait=False, cancel_futures=True)
    _pools.clear()


def _watch_parent(parent_pid: int) -> None:
    """Pool worker start-up: die with the parent, even when it is killed outright (SIGKILL).

    Linux: the kernel signals the worker when its parent dies (``PR_SET_PDEATHSIG``);
    elsewhere a daemon thread polls the parent pid once a second.
    """
    import signal
    import threading
    import time

    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        armed = libc.prctl(1, int(signal.SIGKILL), 0, 0, 0) == 0  # PR_SET_PDEATHSIG = 1
    except (OSError, AttributeError):
        armed = False
    if os.getppid() != parent_pid:  # the parent died before the signal was armed
        os._exit(1)
    if not armed:

        def poll() -> None:
            while os.getppid() == parent_pid:
                time.sleep(1.0)
            os._exit(1)

        threading.Thread(target=poll, name="parent-watch", daemon=True).start()


def pool_results(
    func: Callable[[Any], Any], items: list, workers: int, warm: Warm = None
) -> Iterator[tuple[Any, Any]]:
    """This process and ``workers`` workers warmed by ``warm`` take the items in turn (see above).

    A worker gets an item only when it is warm (its start-up task done) and has none; this
    process runs the next item whenever it has checked the workers.
    """
    pool = _shared_pool(workers, warm)
    todo = deque(items)
    idle: deque = deque()
    busy: dict = {}  # future -> item (None: a worker's start-up task)
    for _ in range(workers):
        busy[pool.submit(_ready)] = None
    try:
        while todo or any(item is not None for item in busy.values()):
            done = (
                [f for f in busy if f.done()]
                if todo
                else list(wait(list(busy), return_when=FIRST_COMPLETED).done)
            )
            for future in done:
                item = busy.pop(future)
                idle.append(future)
                if item is not None:
                    yield item, future.result()
                else:
                    future.result()  # a worker that failed to start raises here
            while idle and todo:
                idle.popleft()
                item = todo.popleft()
                busy[pool.submit(func, item)] = item
            if todo:  # this process takes the next one
                item = todo.popleft()
                yield item, func(item)
    except BaseException:
        for future in busy:
            future.cancel()
        _discard_pool(workers, warm)  # a worker still on an item is stopped, not waited for
        raise


def _discard_pool(workers: int, warm: Warm) -> None:
    pool = _pools.pop((workers, warm), None)
    if pool is None:
        return
    for process in list(getattr(pool, "_processes", {}).values()):
        process.terminate()
    pool.shutdown(wait=False, cancel_futures=True)
