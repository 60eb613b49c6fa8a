"""Running many independent simulations, and writing their files atomically.

:func:`run_all` maps a picklable function over work items, in this process
(``jobs=1``), in this process and ``jobs - 1`` warm worker processes, or on a Dask
cluster (a ``distributed.Client`` from :func:`connect_dask`), with a rich progress
bar on stderr. Results come back to the calling process whichever the executor, so
the caller writes every file itself. The writers put a file in place with one
``os.replace``: a reader, or a rerun after an interruption, sees either the whole
file or none.

The local pool (:func:`worker_pool`): workers are spawned (MuJoCo and its threads
are never forked), die with their parent even when it is killed outright, and
import the twin as they start, in parallel with the caller's own work; a pool is
kept for the life of the process, so a second sweep or suite finds it warm. The
calling process simulates too, taking the next item whenever it is free, and a
worker is handed an item only once it is warm and idle: a worker that is slow to
start never holds an item the caller could have run, so ``jobs=2`` is never slower
than ``jobs=1`` by more than the hand-over of one result.
"""

from __future__ import annotations

import atexit
import json
import multiprocessing
import os
from collections import deque
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator

from amr_twin.recording import atomic_file

EXECUTORS = ("local", "dask")
SCHEDULER_TIMEOUT_S = 5.0  # default time to reach a Dask scheduler, s


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
        raise ValueError(f"--jobs {jobs}: must be in 1..{cores} on this machine ({cores} usable cores; each "
                         "worker is a ~170 MB process simulating on one core, more only add memory)")
    return jobs


def _warm_worker(parent_pid: int) -> None:
    """Pool worker start-up: die with the parent, then import the twin (numpy, MuJoCo, the
    model build and the loop) before the first item arrives."""
    _watch_parent(parent_pid)
    import amr_twin.sim.loop  # noqa: F401
    import amr_twin.sim.run  # noqa: F401


def _ready() -> int:
    """A worker's first task: it is warm when this returns (its pid)."""
    return os.getpid()


def worker_pool(workers: int) -> ProcessPoolExecutor:
    """A new pool of ``workers`` spawned, warm, parent-death-guarded processes (the caller
    shuts it down). :func:`run_all` keeps one per size for the life of the process."""
    context = multiprocessing.get_context("spawn")
    return ProcessPoolExecutor(max_workers=workers, mp_context=context, initializer=_warm_worker,
                               initargs=(os.getpid(),))


_pools: dict[int, ProcessPoolExecutor] = {}


def _shared_pool(workers: int) -> ProcessPoolExecutor:
    """The process' pool of ``workers`` warm workers, made on first use (see :func:`run_all`)."""
    pool = _pools.get(workers)
    if pool is None or getattr(pool, "_broken", False) or getattr(pool, "_shutdown_thread", False):
        pool = _pools[workers] = worker_pool(workers)
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


class ExecutorError(RuntimeError):
    """An executor that cannot be used (Dask not installed, scheduler unreachable); one-line message."""


def connect_dask(address: str, timeout_s: float = SCHEDULER_TIMEOUT_S):
    """Connect to the Dask scheduler at ``address`` (e.g. ``tcp://10.0.0.5:8786``).

    Parameters
    ----------
    address : scheduler address, as printed by ``dask scheduler`` or ``LocalCluster.scheduler_address``.
    timeout_s : give up connecting after this long, s (> 0).

    Returns
    -------
    distributed.Client : the caller closes it (``client.close()``).

    Raises
    ------
    ExecutorError : Dask's ``distributed`` is not installed, or the scheduler did not answer in time.
    """
    if not (timeout_s > 0 and timeout_s < 3600):
        raise ExecutorError(f"scheduler timeout: {timeout_s} s must be in (0, 3600) s")
    try:
        from distributed import Client
    except ImportError:
        raise ExecutorError("--executor dask: dask.distributed is not installed "
                            "(pip install 'amr-twin[dask]'), or use --executor local") from None
    _probe_scheduler(address, timeout_s)
    client = Client.__new__(Client)
    try:
        client.__init__(address, timeout=f"{timeout_s}s", set_as_default=False)
    except Exception as exc:  # noqa: BLE001 - whatever the far end did, one line
        _discard(client)
        detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ExecutorError(f"--scheduler {address!r}: no Dask scheduler answered there within "
                            f"{timeout_s:g} s ({type(exc).__name__}: {detail[:100]})") from None
    return client


def _discard(client) -> None:
    """Stop a Client whose constructor failed, so that its finaliser does not block for 10 s."""
    import contextlib

    with contextlib.suppress(Exception):
        client.status = "closed"
    with contextlib.suppress(Exception):
        client._loop_runner.stop()


def _probe_scheduler(address: str, timeout_s: float) -> None:
    """Open (and close) a TCP connection to a ``tcp://`` scheduler before Dask does.

    A refused, unresolvable or malformed address is reported in one line at once,
    before Dask's own retries.
    """
    import socket

    from distributed.comm import parse_address
    from distributed.comm.addressing import parse_host_port

    try:
        scheme, location = parse_address(address)
        if scheme not in ("tcp", "tls"):
            return
        host, port = parse_host_port(location)
    except (ValueError, TypeError) as exc:
        raise ExecutorError(f"--scheduler {address!r}: not a scheduler address, e.g. tcp://10.0.0.5:8786 "
                            f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
    try:
        socket.create_connection((host, int(port)), timeout=timeout_s).close()
    except OSError as exc:
        reason = "timed out" if isinstance(exc, TimeoutError) else (exc.strerror or str(exc) or type(exc).__name__)
        raise ExecutorError(f"--scheduler {address!r}: cannot reach the Dask scheduler within "
                            f"{timeout_s:g} s ({reason})") from None


def _dask_results(client, func: Callable[[Any], Any], items: list) -> Iterator[tuple[Any, Any]]:
    from distributed import as_completed as dask_as_completed

    if not items:
        return
    futures = client.map(func, items, pure=False)
    item_of = {future.key: item for future, item in zip(futures, items)}
    try:
        for future in dask_as_completed(futures, loop=client.loop):
            yield item_of[future.key], future.result()
    finally:  # interrupted, or a run raised: the cluster drops what is left
        client.cancel([f for f in futures if not f.done()])


def run_all(func: Callable[[Any], Any], items: Iterable[Any], jobs: int = 1,
            description: str = "runs", progress: bool = True, client=None) -> Iterator[tuple[Any, Any]]:
    """Yield ``(item, func(item))`` as each completes (in order when ``jobs == 1`` and no client).

    Parameters
    ----------
    func : a module-level (picklable) function of one item; on a Dask cluster the
        workers must be able to import it (``amr_twin`` installed there).
    items : work items (picklable).
    jobs : worker processes of the local pool; 1 runs in this process. Ignored with ``client``.
    description : label of the progress bar.
    progress : show the rich progress bar (stderr).
    client : a ``distributed.Client`` (see :func:`connect_dask`): run the items on
        its cluster instead of locally. The caller keeps ownership of it.
    """
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    items = list(items)
    if jobs < 1:
        raise ValueError(f"jobs: {jobs} must be >= 1")
    bar = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                   console=Console(stderr=True), disable=not progress, transient=False)
    with bar:
        task = bar.add_task(description, total=len(items))
        if client is not None:
            for item, result in _dask_results(client, func, items):
                bar.advance(task)
                yield item, result
            return
        if jobs == 1 or len(items) <= 1:
            for item in items:
                result = func(item)
                bar.advance(task)
                yield item, result
            return
        for item, result in _with_workers(func, items, min(jobs, len(items)) - 1):
            bar.advance(task)
            yield item, result


def _with_workers(func: Callable[[Any], Any], items: list, workers: int) -> Iterator[tuple[Any, Any]]:
    """This process and ``workers`` warm pool workers take the items in turn (module notes).

    A worker gets an item only when it is warm (its start-up task done) and has none; this
    process runs the next item whenever it has checked the workers.
    """
    pool = _shared_pool(workers)
    todo = deque(items)
    idle: deque = deque()
    busy: dict = {}  # future -> item (None: a worker's start-up task)
    for _ in range(workers):
        busy[pool.submit(_ready)] = None
    try:
        while todo or any(item is not None for item in busy.values()):
            done = [f for f in busy if f.done()] if todo else \
                list(wait(list(busy), return_when=FIRST_COMPLETED).done)
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
        _discard_pool(workers)  # a worker still on an item is stopped, not waited for
        raise


def _discard_pool(workers: int) -> None:
    pool = _pools.pop(workers, None)
    if pool is None:
        return
    for process in list(getattr(pool, "_processes", {}).values()):
        process.terminate()
    pool.shutdown(wait=False, cancel_futures=True)


def write_text(path: Path, text: str) -> None:
    """Write a text file atomically (temporary file in the same folder, then rename)."""
    atomic_file.write_text(path, text)


def write_json(path: Path, obj: Any) -> None:
    """Write ``obj`` as indented JSON, atomically."""
    write_text(path, json.dumps(obj, indent=2, allow_nan=False) + "\n")


def save_figure(fig, path: Path, dpi: int = 110) -> None:
    """Save a matplotlib figure as PNG atomically and close it."""
    import io

    import matplotlib.pyplot as plt

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi)
    plt.close(fig)
    atomic_file.write_bytes(path, buffer.getvalue())
