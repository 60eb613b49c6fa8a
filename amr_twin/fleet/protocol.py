"""VDA 5050 2.0 on MQTT: topic names, message headers and timestamps (the specification's sections
6.3, 6.4).

A topic is ``<interfaceName>/v2/<manufacturer>/<serialNumber>/<topic>``; every message starts with
the header ``headerId`` (counted per topic), ``timestamp`` (ISO 8601, UTC), ``version``,
``manufacturer``, ``serialNumber``. The twin's messages are stamped on its own clock: the wall time
at the start of the run plus the simulated time."""

from __future__ import annotations

import re
from datetime import datetime, timedelta, timezone

VERSION = "2.0.0"
MAJOR = "v2"
MANUFACTURER = "amr-twin"
INTERFACE = "uagv"
SUBTOPICS = ("order", "instantActions", "state", "visualization", "connection", "factsheet")
QOS = {
    "order": 0,
    "instantActions": 0,
    "state": 0,
    "visualization": 0,
    "connection": 1,
    "factsheet": 0,
}
"""Quality of service by subtopic: 0 for order, state and visualization, 1 for connection (section
6.2)."""
_NAME = re.compile(r"^[A-Za-z0-9_.:-]+$")


def check_name(what: str, value: str) -> str:
    """``value`` if it may stand as a topic level (A-Z a-z 0-9 _ . : -, section 6.3); ValueError
    naming ``what``."""
    if not _NAME.match(value):
        raise ValueError(
            f"{what} {value!r}: only letters, digits and _ . : - are allowed (VDA 5050 topic level)"
        )
    return value


def topic(interface: str, serial: str, subtopic: str, manufacturer: str = MANUFACTURER) -> str:
    """The MQTT topic of ``subtopic`` for vehicle ``serial``."""
    return f"{interface}/{MAJOR}/{manufacturer}/{serial}/{subtopic}"


def serial_numbers(robots: int) -> list[str]:
    """The serial numbers of a fleet of ``robots``: amr-1 .. amr-N."""
    return [f"amr-{i}" for i in range(1, robots + 1)]


class Stamper:
    """Headers of one vehicle's messages: ``headerId`` per topic from 0, the timestamp from the
    twin's clock."""

    def __init__(
        self, serial: str, epoch: datetime | None = None, manufacturer: str = MANUFACTURER
    ):
        self.serial, self.manufacturer = serial, manufacturer
        self.epoch = epoch if epoch is not None else datetime.now(timezone.utc)
        self._ids: dict[str, int] = {}

    def timestamp(self, t_s: float) -> str:
        """``t_s`` s of simulated time after the epoch, as ``YYYY-MM-DDTHH:MM:SS.sssZ``."""
        t = self.epoch + timedelta(seconds=t_s)
        return t.strftime("%Y-%m-%dT%H:%M:%S.") + f"{t.microsecond // 1000:03d}Z"

    def header(self, subtopic: str, t_s: float) -> dict:
        """The next header of ``subtopic`` at simulated time ``t_s``."""
        n = self._ids.get(subtopic, 0)
        self._ids[subtopic] = n + 1
        return {
            "headerId": n,
            "timestamp": self.timestamp(t_s),
            "version": VERSION,
            "manufacturer": self.manufacturer,
            "serialNumber": self.serial,
        }
