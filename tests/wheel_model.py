"""A first-order wheel model with hall edges, for the firmware unit tests (no mujoco).

``speed' = (k * duty * dir - speed) / tau`` per wheel, integrated exactly between clock
events and 1 ms ticks; the SC edges of :class:`HallSensors` go to the firmware's ISR.
"""

import math

import numpy as np

from amr_twin.model.config import load_config
from amr_twin.sensors.hall import HallSensors

WHEEL = load_config().wheel

K_RPM = 1054.0 / 0.9  # duty 0.9*sp/1054 -> sp
TAU_S = 0.25  # time constant, s


def simulate(fw, clock, t_end_us, state=None):
    """First-order wheel model (speed' = (k*duty*dir - speed)/tau) with hall edges."""
    hall, speed, angle = state or (
        HallSensors(pole_pairs=WHEEL.hall_pole_pairs),
        np.zeros(2),
        np.zeros(2),
    )
    while clock.now_us < t_end_us:
        t0 = clock.now_us
        t1 = min(t0 - t0 % 1000 + 1000, clock.next_event_us(), t_end_us)
        dt = (t1 - t0) * 1e-6
        drive = [p.enabled and not p.braking for p in fw.pins]
        tgt = np.array([K_RPM * p.duty * p.direction if d else 0.0 for p, d in zip(fw.pins, drive)])
        tau = np.array([0.02 if p.braking else (TAU_S if p.enabled else 2.0) for p in fw.pins])
        e = np.exp(-dt / tau)
        new_angle = angle + (tgt * dt + (speed - tgt) * tau * (1 - e)) * 2 * math.pi / 60
        speed = tgt + (speed - tgt) * e
        for t, w in zip(*hall.edges(np.array([t0, t1]), np.vstack([angle, new_angle]))):
            clock.set_time(int(t))
            fw.on_sc_edge(int(w))
        angle = new_angle
        clock.run_until(t1)
    return hall, speed, angle
