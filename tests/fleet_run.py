"""A short recorded run of three robots (the recording tests' fixture): each robot served as a
VDA 5050 vehicle standing at its start, the whole world captured and written."""

from __future__ import annotations

STARTS = ((0.0, 0.0, 0.0), (2.0, 0.0, 0.0), (-2.0, 0.0, 3.14159))
DURATION_S = 3.0


def record_fleet(out, starts=STARTS, duration_s: float = DURATION_S):
    """Run ``starts`` robots on ``aisles`` for ``duration_s`` simulated s as fast as possible and
    write ``out/fleet.mcap`` and ``out/fleet.rrd``; returns (captures, mcap path, rrd path)."""
    from amr_twin.fleet.session import FleetOptions, FleetSession
    from amr_twin.model.config import load_config
    from amr_twin.model.urdf import robot_urdf
    from amr_twin.recording.fleet_capture import attach_fleet
    from amr_twin.recording.fleet_mcap import write_fleet_mcap
    from amr_twin.recording.fleet_rrd import write_fleet_rrd

    cfg = load_config()
    session = FleetSession(cfg, FleetOptions(world="aisles", starts=tuple(starts), rate=0))
    try:
        captures = attach_fleet(session.world, names=session.serials)
        session.run(duration_s)
    finally:
        session.close()
    mcap = write_fleet_mcap(captures, out / "fleet.mcap", robot_urdf(cfg))
    rrd = write_fleet_rrd(captures, out / "fleet.rrd")
    return captures, mcap, rrd
