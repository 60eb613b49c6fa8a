"""The capture of a running twin, and the file names recordings are written through.

Stage 1 of a recording (stage 2, writing the files, is :mod:`amr_twin.recording.rerun_log` and
:mod:`amr_twin.recording.mcap_log`): a :class:`Capture` is attached to a
:class:`~amr_twin.assembly.twin.Twin` before it runs. It taps the bus (keeps every published
message with its time, us) and samples the world pose of each robot body as a grid
sampler of the loop (default ~30 Hz on the recorder's 10 ms grid; no clock event, so
the physics chunks, hence the run, are unchanged), and the joint and base state on
every grid instant for the ROS messages of :mod:`amr_twin.ros.ros_state` (joint states,
link transforms, ground truth). It reads the twin through its hooks and observables.

Both writers write a temporary file next to the target and rename it when complete
(:mod:`amr_twin.base.atomic_file`); :func:`recording_folder` prepares a folder of per-run
recordings and removes the temporaries that killed writers left there.
"""

from __future__ import annotations

import weakref
from pathlib import Path

import numpy as np

from amr_twin.recording.recorder import attach_recorder

US = 1_000_000

_captures: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


class Capture:
    """Bus messages and body poses of a running twin (attach before running).

    The body poses are taken by a grid sampler of the loop (``twin.on_grid``,
    called on the record grid while the physics steps), not by a clock event: the
    capture adds no boundary to the physics chunks, so a recorded run is the same
    run whatever the caller's ``advance`` pattern (a sweep's 20 ms loop included).
    """

    def __init__(self, twin, body_hz: float = 30.0, prefix: str = "amr/", bodies=None):
        """``prefix``: the robot's names in the model (``amr-2/`` in a fleet); ``bodies``: the
        ids of the bodies whose poses to keep (None: every body but the world)."""
        self.twin = twin
        self.messages: dict[str, list[tuple[int, object]]] = {}
        m = twin.observables.model
        self.body_ids = np.array(
            [b for b in range(1, m.nbody)] if bodies is None else list(bodies), dtype=int
        )
        self._xpos, self._xquat = (
            twin.observables.named.data.xpos,
            twin.observables.named.data.xquat,
        )
        grid_us = twin.grid_us
        self.period_us = max(grid_us, int(round(US / body_hz / grid_us)) * grid_us)
        self._t: list[int] = []
        self._pos: list[np.ndarray] = []
        self._quat: list[np.ndarray] = []
        from amr_twin.ros.ros_state import StateSampler

        self.state = StateSampler(m, twin.observables.named, prefix=prefix)
        """Joint and base state on every grid instant (:mod:`amr_twin.ros.ros_state`)."""
        twin.on_message(self._tap)
        self._sample(twin.t_phys_us)
        self.state.sample(twin.t_phys_us)
        twin.on_grid(self._on_grid)
        _captures[twin] = self

    def _tap(self, topic: str, msg, t_us: int) -> None:
        lst = self.messages.get(topic)
        if lst is None:
            lst = self.messages[topic] = []
        lst.append((t_us, msg))

    def _sample(self, t_us: int) -> None:
        ids = self.body_ids
        self._t.append(int(t_us))
        self._pos.append(self._xpos[ids].copy())
        self._quat.append(self._xquat[ids].copy())

    def _on_grid(self, t_us: int) -> None:
        """Grid sampler: the physics is at ``t_us``; keep the poses every ``period_us``, the state
        always."""
        self.state.sample(t_us)
        if t_us % self.period_us == 0 and t_us > self._t[-1]:
            self._sample(t_us)

    def body_poses(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """t_s (n,), positions (n, nb, 3), quaternions w x y z (n, nb, 4)."""
        return (
            np.array(self._t, float) / US,
            np.array(self._pos).reshape(-1, len(self.body_ids), 3),
            np.array(self._quat).reshape(-1, len(self.body_ids), 4),
        )


def attach(twin, body_hz: float = 30.0) -> Capture:
    """Start capturing ``twin`` (before it runs), its series with it (its recorder); returns the
    :class:`Capture`.

    Raises ValueError for a twin built without the robot's visuals (``TwinOptions(visuals=False)``).
    """
    if not twin.options.visuals:
        raise ValueError(
            "a recording draws the robot: build the twin with TwinOptions(visuals=True)"
        )
    capture = _captures.get(twin) or Capture(twin, body_hz)
    attach_recorder(twin)  # the series the recordings write
    return capture


def capture_of(twin) -> Capture | None:
    """The :class:`Capture` attached to ``twin``, or None if it was not attached."""
    return _captures.get(twin)


def remove_stale_temporaries(folder: Path) -> list[Path]:
    """Delete the half-written recordings killed writers left in ``folder``; return them.

    See :func:`amr_twin.base.atomic_file.remove_stale_temporaries`: a temporary whose writer
    (the pid in its name) still runs is left alone.
    """
    from amr_twin.base.atomic_file import remove_stale_temporaries as remove_stale

    return remove_stale(folder)


def recording_folder(folder: Path) -> Path:
    """``folder`` made absolute (worker processes may run elsewhere), created, stale temporaries
    removed."""
    folder = Path(folder).resolve()
    folder.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(folder)
    return folder
