"""The UWB tag's ranges in a ``.rrd`` recording (:func:`_log_uwb`), on the ``sim_time`` timeline::

    uwb/anchor_<i>/range_m              Scalars, one per received range (only with a UWB tag)
    world/uwb/anchors                   static Points3D of the anchors
    world/uwb/anchor_<i>/ray            LineStrips3D tag -> anchor at each range

Positions in m in the simulation's world frame (Z up).
"""

from __future__ import annotations

import numpy as np

from amr_twin.recording.rerun_capture import Capture
from amr_twin.recording.rerun_streams import _scalars, _time
from amr_twin.recording.rerun_world import _body_pose_at


def uwb_geometry(twin) -> tuple[np.ndarray, np.ndarray]:
    """Anchor positions (K, 3) in the world and the tag position (3,) in ``base_link``, m.

    From the twin's UWB sensor (``twin.sensors["uwb"]``) when it has one, else from
    ``twin.cfg.uwb``."""
    sensor = twin.sensors.get("uwb")
    if sensor is not None:
        return np.asarray(sensor.anchors_xyz_m, float), np.asarray(sensor.tag_pos_m, float)
    u = twin.cfg.uwb
    anchors = np.column_stack(
        [np.asarray(u.anchors_xy_m, float), np.full(len(u.anchors_x_m), u.anchor_z_m)]
    )
    return anchors, np.asarray(u.tag_pos_m, float)


def uwb_ranges(capture: Capture) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """The captured ``uwb/range`` messages per anchor: ``{i: (stamp t_s (n,), range_m (n,))}``."""
    from amr_twin.sensors.uwb import anchor_index

    per: dict[int, tuple[list, list]] = {}
    for _t_us, msg in capture.messages.get("uwb/range", []):
        t, r = per.setdefault(anchor_index(msg.header.frame_id), ([], []))
        t.append(msg.header.stamp.to_sec())
        r.append(float(msg.range))
    return {i: (np.array(t), np.array(r)) for i, (t, r) in sorted(per.items())}


def _log_uwb(
    rec, m, capture: Capture, base: str = "amr/base_link", root: str = "", anchors: bool = True
) -> bool:
    """Ranges per anchor as scalars (``<root>uwb/anchor_<i>/range_m``), the anchors (unless
    ``anchors`` is false: another robot's logged them), and a line from the tag to each anchor
    ranged (``world/<root>uwb/anchor_<i>/ray``; ``base``: the robot's base body). Returns
    whether there were ranges.

    The tag's world position at a range's stamp uses the base's interpolated
    position and yaw (the base's small tilt is left out of the line).
    """
    import rerun as rr

    ranges = uwb_ranges(capture)
    if not ranges:
        return False
    anchors_xyz, tag = uwb_geometry(capture.twin)
    if anchors:
        rec.log(
            "world/uwb/anchors",
            rr.Points3D(
                anchors_xyz,
                radii=[0.08],
                colors=[(200, 60, 200)],
                labels=[f"anchor_{i}" for i in range(len(anchors_xyz))],
            ),
            static=True,
        )
    for i, (t_s, range_m) in ranges.items():
        _scalars(rec, f"{root}uwb/anchor_{i}/range_m", t_s, range_m)
        if i >= len(anchors_xyz):
            continue
        p, yaw = _body_pose_at(capture, m, base, t_s)
        c, s = np.cos(yaw), np.sin(yaw)
        tag_w = np.column_stack(
            [p[:, 0] + c * tag[0] - s * tag[1], p[:, 1] + s * tag[0] + c * tag[1], p[:, 2] + tag[2]]
        )
        strips = np.stack(
            [tag_w, np.broadcast_to(anchors_xyz[i], tag_w.shape)], axis=1
        )  # (n, 2, 3)
        rec.send_columns(
            f"world/{root}uwb/anchor_{i}/ray",
            indexes=_time(t_s),
            columns=rr.LineStrips3D.columns(strips=strips),
        )
        rec.log(
            f"world/{root}uwb/anchor_{i}/ray",
            rr.LineStrips3D.from_fields(colors=[(200, 60, 200)], radii=[0.005]),
            static=True,
        )
    return True
