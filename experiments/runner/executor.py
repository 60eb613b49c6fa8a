"""Running many independent simulations, and writing their files atomically.

:func:`run_all` maps a picklable function over work items, in this process
(``jobs=1``), in this process and ``jobs - 1`` warm worker processes, or on a Dask
cluster (a ``distributed.Client`` from :func:`~.dask_cluster.connect_dask`), with a rich progress
bar on stderr. Results come back to the calling process whichever the executor, so
the caller writes every file itself. The writers put a file in place with one
``os.replace``: a reader, or a rerun after an interruption, sees either the whole
file or none.

The local pool is in :mod:`amr_twin.base.process_pool` (its workers warmed by
:func:`amr_twin.recording.run.warm_up`), the Dask cluster in :mod:`.dask_cluster`
(:func:`~.dask_cluster.connect_dask`)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator

from amr_twin.base import atomic_file
from amr_twin.base.process_pool import pool_results
from amr_twin.experiments.runner.dask_cluster import cluster_results

EXECUTORS = ("local", "dask")


def run_all(
    func: Callable[[Any], Any],
    items: Iterable[Any],
    jobs: int = 1,
    description: str = "runs",
    progress: bool = True,
    client=None,
    size: Callable[[Any], int] | None = None,
) -> Iterator[tuple[Any, Any]]:
    """Yield ``(item, func(item))`` as each completes (in order when ``jobs == 1`` and no client).

    Parameters
    ----------
    func : a module-level (picklable) function of one item; on a Dask cluster the
        workers must be able to import it (``amr_twin`` installed there).
    items : work items (picklable).
    jobs : worker processes of the local pool; 1 runs in this process. Ignored with ``client``.
    description : label of the progress bar.
    progress : show the rich progress bar (stderr).
    client : a ``distributed.Client`` (see :func:`~.dask_cluster.connect_dask`): run the items on
        its cluster instead of locally. The caller keeps ownership of it.
    size : how many runs an item holds (the progress bar counts runs); 1 each when None.
    """
    items = list(items)
    if jobs < 1:
        raise ValueError(f"jobs: {jobs} must be >= 1")
    size = size or (lambda item: 1)
    with _progress_bar(progress) as bar:
        task = bar.add_task(description, total=sum(size(item) for item in items))
        if client is not None:
            for item, result in cluster_results(client, func, items):
                bar.advance(task, size(item))
                yield item, result
            return
        if jobs == 1 or len(items) <= 1:
            for item in items:
                result = func(item)
                bar.advance(task, size(item))
                yield item, result
            return
        from amr_twin.recording.run import (
            warm_up,
        )  # the twin, imported by the workers as they start

        for item, result in pool_results(func, items, min(jobs, len(items)) - 1, warm_up):
            bar.advance(task, size(item))
            yield item, result


class _NoBar:
    """What :func:`run_all` asks of a progress bar, doing nothing (rich is not imported: ~70 ms)."""

    def __enter__(self) -> "_NoBar":
        return self

    def __exit__(self, *exc) -> None:
        return None

    def add_task(self, description: str, total: int) -> int:
        return 0

    def advance(self, task: int, runs: int = 1) -> None:
        return None


def _progress_bar(progress: bool):
    """A rich progress bar on stderr, or :class:`_NoBar` without ``progress``."""
    if not progress:
        return _NoBar()
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    return Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=Console(stderr=True),
        transient=False,
    )


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
