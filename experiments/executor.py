"""Running many independent simulations, and writing their files atomically.

:func:`run_all` maps a picklable function over work items, in this process
(``jobs=1``) or in a pool of ``jobs`` worker processes (spawned, so MuJoCo and
its threads are never forked), with a rich progress bar on stderr. The writers
put a file in place with one ``os.replace``: a reader, or a rerun after an
interruption, sees either the whole file or none.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import tempfile
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator


def run_all(func: Callable[[Any], Any], items: Iterable[Any], jobs: int = 1,
            description: str = "runs", progress: bool = True) -> Iterator[tuple[Any, Any]]:
    """Yield ``(item, func(item))`` as each completes (in order when ``jobs == 1``).

    Parameters
    ----------
    func : a module-level (picklable) function of one item.
    items : work items (picklable).
    jobs : worker processes; 1 runs in this process.
    description : label of the progress bar.
    progress : show the rich progress bar (stderr).
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


def _write_bytes_atomic(path: Path, data: bytes) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_text(path: Path, text: str) -> None:
    """Write a text file atomically (temporary file in the same folder, then rename)."""
    _write_bytes_atomic(path, text.encode())


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
    _write_bytes_atomic(path, buffer.getvalue())
