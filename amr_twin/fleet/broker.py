"""An embedded MQTT broker (amqtt, pure Python) on its own thread, for a run without
``--vda5050``."""

from __future__ import annotations

import asyncio
import logging
import socket
import threading


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port free on ``host`` now."""
    with socket.socket() as s:
        s.bind((host, 0))
        return s.getsockname()[1]


class EmbeddedBroker:
    """amqtt's broker listening on ``host:port`` (0: a free port), anonymous clients allowed;
    :meth:`stop` ends it."""

    def __init__(self, host: str = "127.0.0.1", port: int = 0):
        self.host, self.port = host, port or free_port(host)
        self._loop = asyncio.new_event_loop()
        self._broker = None
        self._thread: threading.Thread | None = None

    @property
    def url(self) -> str:
        return f"mqtt://{self.host}:{self.port}"

    def start(self, timeout_s: float = 10.0) -> "EmbeddedBroker":
        """Start serving; OSError if it could not within ``timeout_s``."""
        from amqtt.broker import Broker

        logging.getLogger("amqtt").setLevel(
            logging.ERROR
        )  # its per-message notes are not the run's
        ready, failed = threading.Event(), []
        config = {
            "listeners": {"default": {"type": "tcp", "bind": f"{self.host}:{self.port}"}},
            "plugins": {
                "amqtt.plugins.authentication.AnonymousAuthPlugin": {"allow_anonymous": True}
            },
        }

        def serve() -> None:
            asyncio.set_event_loop(self._loop)

            async def begin() -> None:
                self._broker = Broker(config, loop=self._loop)
                await self._broker.start()

            try:
                self._loop.run_until_complete(begin())
            except Exception as exc:  # noqa: BLE001 - reported to the starting thread
                failed.append(exc)
                ready.set()
                return
            ready.set()
            self._loop.run_forever()

        self._thread = threading.Thread(target=serve, name="amqtt-broker", daemon=True)
        self._thread.start()
        if not ready.wait(timeout_s) or failed:
            raise OSError(
                f"the embedded MQTT broker could not listen on {self.host}:{self.port}"
                + (f" ({failed[0]})" if failed else "")
            )
        return self

    def stop(self) -> None:
        """Shut the broker down and end its thread."""
        if self._broker is not None:
            # amqtt waits for its clients' sessions: a client that hangs on must not hold the run
            try:
                asyncio.run_coroutine_threadsafe(self._broker.shutdown(), self._loop).result(5.0)
            except TimeoutError:
                pass
            self._broker = None
        self._loop.call_soon_threadsafe(self._loop.stop)
        if self._thread is not None:
            self._thread.join(10.0)
