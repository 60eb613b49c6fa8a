"""rospy's node shut down with its server threads ended: :func:`shut_down`.

Reasons and measurements: docs/how-to/ros1.md#amr_twinros1node_shutdown."""

from __future__ import annotations

import os
import socket
import sys
import threading
import time

JOIN_S = 5.0
"""Longest wait for rospy's server threads to end after its shutdown, wall s."""


def _loop_codes() -> dict:
    """The code of each server loop rospy leaves running -> what it serves: rosgraph's XML-RPC node
    (``XmlRpcNode._run``), socketserver's loop inside it, and rospy's TCPROS listener."""
    from socketserver import BaseServer

    from rosgraph.xmlrpc import XmlRpcNode
    from rospy.impl.tcpros_base import TCPServer

    return {
        XmlRpcNode._run.__code__: "xmlrpc",
        BaseServer.serve_forever.__code__: "serve",
        TCPServer.run.__code__: "tcpros",
    }


def server_loops() -> list[tuple[int, str, object]]:
    """``(thread id, kind, server)`` of each rospy server loop on a thread's stack now; kind is
    ``"xmlrpc"``, ``"serve"`` (its socketserver) or ``"tcpros"``, server the loop's ``self``."""
    codes, found = _loop_codes(), []
    for ident, frame in sys._current_frames().items():
        while frame is not None:
            kind = codes.get(frame.f_code)
            if kind is not None:
                found.append((ident, kind, frame.f_locals.get("self")))
            frame = frame.f_back
    return found


def shut_down(rospy, reason: str, join_s: float = JOIN_S) -> list[str]:
    """``rospy.signal_shutdown(reason)``, then end the two server threads it leaves running: the
    XML-RPC server's (its loop stopped) and the TCPROS listener's (its socket shut, which wakes
    ``accept``; a close does not). Waits for them at most ``join_s``; returns the names of the
    threads still running a server loop then (empty: all ended)."""
    loops = server_loops()
    listeners = [  # dups: rospy closes its own descriptors
        os.dup(s.server_sock.fileno())
        for _i, kind, s in loops
        if kind == "tcpros" and s.server_sock is not None and s.server_sock.fileno() >= 0
    ]
    rospy.signal_shutdown(reason)
    for fd in listeners:
        with socket.socket(fileno=fd) as sock:
            try:
                sock.shutdown(socket.SHUT_RDWR)
            except OSError:  # not connected or gone: accept has already returned
                pass
    for _i, kind, server in loops:
        if kind == "serve":  # serve_forever is running: shutdown() returns within its poll
            server.shutdown()
    return _wait({ident for ident, _k, _s in loops}, join_s)


def _wait(idents: set[int], join_s: float) -> list[str]:
    deadline = time.monotonic() + join_s
    left = idents
    while left and time.monotonic() < deadline:
        time.sleep(0.005)
        left = {ident for ident, _k, _s in server_loops()} & idents
    for thread in threading.enumerate():  # the threading threads' last steps after their loop
        if thread.ident in idents and type(thread).join is threading.Thread.join:  # no dummy
            thread.join(max(0.0, deadline - time.monotonic()))
    named = {t.ident: t.name for t in threading.enumerate()}
    return [named.get(ident, str(ident)) for ident in sorted(left)]
