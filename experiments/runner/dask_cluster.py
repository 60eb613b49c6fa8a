"""Running work items on a Dask cluster: connecting to its scheduler, and mapping over its workers.

A scheduler that cannot be used (Dask not installed, an address that is malformed,
refused or silent) is reported as one :class:`ExecutorError` line before Dask's own
retries.
"""

from __future__ import annotations

from typing import Any, Callable, Iterator

SCHEDULER_TIMEOUT_S = 5.0  # default time to reach a Dask scheduler, s


class ExecutorError(RuntimeError):
    """An executor that cannot be used (Dask not installed, scheduler unreachable); one-line
    message."""


def connect_dask(address: str, timeout_s: float = SCHEDULER_TIMEOUT_S):
    """Connect to the Dask scheduler at ``address`` (e.g. ``tcp://10.0.0.5:8786``).

    Parameters
    ----------
    address : scheduler address, as printed by ``dask scheduler`` or
    ``LocalCluster.scheduler_address``. timeout_s : give up connecting after this long, s (> 0).

    Returns
    -------
    distributed.Client : the caller closes it (``client.close()``).

    Raises
    ------
    ExecutorError : Dask's ``distributed`` is not installed, or the scheduler did not answer in
    time."""
    if not (timeout_s > 0 and timeout_s < 3600):
        raise ExecutorError(f"scheduler timeout: {timeout_s} s must be in (0, 3600) s")
    try:
        from distributed import Client
    except ImportError:
        raise ExecutorError(
            "--executor dask: dask.distributed is not installed "
            "(pip install 'amr-twin[dask]'), or use --executor local"
        ) from None
    _probe_scheduler(address, timeout_s)
    client = Client.__new__(Client)
    try:
        client.__init__(address, timeout=f"{timeout_s}s", set_as_default=False)
    except Exception as exc:  # noqa: BLE001 - whatever the far end did, one line
        _discard(client)
        detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ExecutorError(
            f"--scheduler {address!r}: no Dask scheduler answered there within "
            f"{timeout_s:g} s ({type(exc).__name__}: {detail[:100]})"
        ) from None
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
        raise ExecutorError(
            f"--scheduler {address!r}: not a scheduler address, e.g. tcp://10.0.0.5:8786 "
            f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})"
        ) from None
    try:
        socket.create_connection((host, int(port)), timeout=timeout_s).close()
    except OSError as exc:
        reason = (
            "timed out"
            if isinstance(exc, TimeoutError)
            else (exc.strerror or str(exc) or type(exc).__name__)
        )
        raise ExecutorError(
            f"--scheduler {address!r}: cannot reach the Dask scheduler within "
            f"{timeout_s:g} s ({reason})"
        ) from None


def cluster_results(client, func: Callable[[Any], Any], items: list) -> Iterator[tuple[Any, Any]]:
    """Yield ``(item, func(item))`` from the cluster of ``client`` as each completes; a run that
    raises raises here, and what is left is cancelled when the caller stops early."""
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
