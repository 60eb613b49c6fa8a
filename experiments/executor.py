"""Running many independent simulations, and writing their files atomically.

:func:`run_all` maps a picklable function over work items, in this process
(``jobs=1``), in a pool of ``jobs`` worker processes (spawned, so MuJoCo and
its threads are never forked), or on a Dask cluster (a ``distributed.Client``
from :func:`connect_dask`), with a rich progress bar on stderr. Results come
back to the calling process whichever the executor, so the caller writes every
file itself. The writers put a file in place with one ``os.replace``: a reader,
or a rerun after an interruption, sees either the whole file or none.
"""

from __future__ import annotations

import json
import multiprocessing
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator

from .. import atomic_file

EXECUTORS = ("local", "dask")
SCHEDULER_TIMEOUT_S = 5.0  # default time to reach a Dask scheduler, s


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
    try:
        return Client(address, timeout=f"{timeout_s}s", set_as_default=False)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ExecutorError(f"--scheduler {address!r}: cannot reach the Dask scheduler within "
                            f"{timeout_s:g} s ({detail})") from None


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
        context = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=min(jobs, len(items)), mp_context=context) as pool:
            futures = {pool.submit(func, item): item for item in items}
            try:
                for future in as_completed(futures):
                    bar.advance(task)
                    yield futures[future], future.result()
            except BaseException:
                for future in futures:
                    future.cancel()
                raise


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
