"""The ROS 1 master the twin joins: the one at ``ROS_MASTER_URI``, or a private ``roscore`` on a
free port.

:func:`master_problem` asks a master for its pid over XML-RPC (the master API's ``getPid``) with a
timeout, without importing ROS: a twin told to join a master that does not answer stops before it
simulates anything. :func:`start_roscore` starts ``roscore -p PORT`` on a free loopback port and
waits until its master answers; the child is asked to stop (SIGINT, as Ctrl-C) when the twin closes
it, and the kernel sends it SIGTERM if the twin dies first (``PR_SET_PDEATHSIG``), on which
roslaunch stops the master and rosout it started: no orphan is left.
"""

from __future__ import annotations

import ctypes
import os
import signal
import socket
import subprocess
import tempfile
import time
import xmlrpc.client
from dataclasses import dataclass, field
from urllib.parse import urlparse

DEFAULT_MASTER_URI = "http://localhost:11311"
"""ROS 1's default when ``ROS_MASTER_URI`` is unset."""


class _TimeoutTransport(xmlrpc.client.Transport):
    def __init__(self, timeout_s: float):
        super().__init__()
        self.timeout_s = timeout_s

    def make_connection(self, host):
        conn = super().make_connection(host)
        conn.timeout = self.timeout_s
        return conn


def master_problem(uri: str, timeout_s: float = 3.0) -> str | None:
    """Why the master at ``uri`` cannot be joined now (None: it answers ``getPid`` within
    ``timeout_s``)."""
    parsed = urlparse(uri)
    if parsed.scheme != "http" or not parsed.hostname or parsed.port is None:
        return f"ROS_MASTER_URI={uri!r} is not of the form http://HOST:PORT"
    try:
        proxy = xmlrpc.client.ServerProxy(uri, transport=_TimeoutTransport(timeout_s))
        code, _msg, _pid = proxy.getPid("/amr_twin_check")
    except (OSError, xmlrpc.client.Error) as exc:
        why = getattr(exc, "strerror", None) or type(exc).__name__
        return f"no ROS master answers at ROS_MASTER_URI={uri} within {timeout_s:g} s ({why})"
    if code != 1:
        return f"the ROS master at {uri} refused getPid (code {code})"
    return None


def master_pid(uri: str, timeout_s: float = 1.0) -> int | None:
    """The pid of the master answering at ``uri`` within ``timeout_s`` (None: none answers): a new
    pid is a new master, which knows nothing of the nodes registered with the one before."""
    try:
        code, _msg, pid = xmlrpc.client.ServerProxy(
            uri, transport=_TimeoutTransport(timeout_s)
        ).getPid("/amr_twin_check")
    except (OSError, xmlrpc.client.Error):
        return None
    return int(pid) if code == 1 else None


def free_port() -> int:
    """A TCP port free on the loopback interface now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _die_with_parent() -> None:
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(1, int(signal.SIGTERM), 0, 0, 0)  # PR_SET_PDEATHSIG = 1


@dataclass
class Master:
    """A master's URI, and the ``roscore`` process when the twin started it (None: joined)."""

    uri: str
    process: subprocess.Popen | None = field(default=None, repr=False)

    def stop(self, timeout_s: float = 10.0) -> None:
        """Stop the private roscore (SIGINT, then SIGKILL of its group after ``timeout_s``); nothing
        for a joined master."""
        proc, self.process = self.process, None
        if proc is None or proc.poll() is not None:
            return
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout_s)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def start_roscore(
    timeout_s: float = 30.0, log_dir: str | None = None, port: int | None = None
) -> Master:
    """``roscore -p PORT`` on ``port`` (None: a free one), once its master answers (RuntimeError,
    one line, if it does not)."""
    port = free_port() if port is None else port
    uri = f"http://127.0.0.1:{port}"
    env = dict(os.environ, ROS_MASTER_URI=uri, ROS_IP="127.0.0.1")
    env.pop("ROS_HOSTNAME", None)
    if log_dir is not None:
        env["ROS_LOG_DIR"] = log_dir
    err = tempfile.TemporaryFile()  # roscore's own messages, read only if it fails to start
    proc = subprocess.Popen(
        ["roscore", "-p", str(port)],
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=err,
        preexec_fn=_die_with_parent,
        start_new_session=True,
    )
    master = Master(uri, proc)
    deadline = time.monotonic() + timeout_s
    while master_problem(uri, 1.0) is not None:
        if proc.poll() is not None:
            err.seek(0)
            lines = err.read().decode(errors="replace").strip().splitlines()
            raise RuntimeError(f"roscore -p {port} exited ({lines[-1] if lines else 'no message'})")
        if time.monotonic() > deadline:
            master.stop()
            raise RuntimeError(f"roscore -p {port} did not answer within {timeout_s:g} s")
        time.sleep(0.1)
    return master
