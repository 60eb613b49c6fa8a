"""A run of one topic's messages written at once, for the bridge's grid-sampled topics:
:class:`StateBlocks` (a tick's at once: :meth:`StateBlocks.blocks`, in C where its helper
``frame_blocks.c`` builds), :func:`clock_block`, :func:`float64_rows_block`, :func:`battery_block`
(a tick's rows in one call of the same helper: :meth:`amr_twin.ros1.row_feed.RowFeed.blocks`).

Each gives the TCPROS frames (a uint32 length, then the message in the ROS 1 format, the bytes genpy
writes: ``tests/ros1/test_frame_blocks.py``) of n messages of one type, one after the other, from a
numpy record array filled column by column: no Python work a message. Every frame of a block has the
same length (``len(block) // n``); :meth:`amr_twin.ros1.outbox.Outbox.put_block` files each under
its instant."""

from __future__ import annotations

import ctypes
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from amr_twin.base.native_build import address, c_array, open_helper

C_SOURCE = Path(__file__).with_name("frame_blocks.c")

_I = struct.Struct("<I")
_U4, _F8 = "<u4", "<f8"


def _string(text: str) -> bytes:
    data = text.encode()
    return _I.pack(len(data)) + data


def _stamps(t_us) -> tuple[np.ndarray, np.ndarray]:
    """ROS ``time`` of instants ``t_us`` (us): seconds and nanoseconds."""
    t = np.asarray(t_us, np.int64)
    return t // 1_000_000, t % 1_000_000 * 1000


class _Layout:
    """A frame's packed record dtype (``len``, then ``fields``) and a record with its constants
    filled in: the frame's length after ``len`` and ``constants`` (field -> value)."""

    def __init__(self, fields: list, constants: dict | None = None):
        dtype = np.dtype([("len", _U4), *fields])
        self.template = np.zeros(1, dtype)
        self.template["len"] = dtype.itemsize - 4
        for name, value in (constants or {}).items():
            self.template[name] = value

    def records(self, n: int) -> np.ndarray:
        """n copies of the template, to fill."""
        return np.repeat(self.template, n)


@dataclass(frozen=True)
class TickBlocks:
    """A tick's state blocks (:meth:`StateBlocks.blocks`): the ground truths at ``t_us`` (every
    sample), the joint states and link transforms at ``kept_us``; None where not asked for."""

    t_us: list[int]
    ground_truth: bytes | None
    kept_us: list[int]
    joint_states: bytes | None
    link_transforms: bytes | None


class StateBlocks:
    """``sensor_msgs/JointState``, the moving links' ``tf2_msgs/TFMessage`` and the ground truth's
    ``nav_msgs/Odometry`` of grid samples (the arrays of
    :meth:`amr_twin.ros.ros_state.StateSampler.arrays`), a block each: the messages of
    :func:`amr_twin.ros.ros_state.joint_state`, ``link_transforms`` and ``ground_truth``.
    ``native=False``: :meth:`blocks` in Python only (the same bytes)."""

    def __init__(
        self, joint_names, child_frames, parent: str, world: str = "world", native: bool = True
    ):
        n = len(joint_names)
        names = b"".join(_string(name) for name in joint_names)
        head = np.void(
            _I.pack(0) + _I.pack(n) + names + _I.pack(n)
        )  # frame_id "", the names, q's count
        self._js = _Layout(
            [
                ("seq", _U4),
                ("stamp", _U4, (2,)),
                ("head", head.dtype),
                ("q", _F8, (n,)),
                ("nqd", _U4),
                ("qd", _F8, (n,)),
                ("neffort", _U4),
            ],
            {"head": head, "nqd": n},
        )
        self._k = len(child_frames)
        fields, constants = [("count", _U4)], {"count": self._k}
        for i, child in enumerate(child_frames):
            blob = np.void(_string(parent) + _string(child))
            fields += [
                (f"stamp{i}", _U4, (3,)),
                (f"frames{i}", blob.dtype),
                (f"pose{i}", _F8, (7,)),
            ]
            constants[f"frames{i}"] = blob
        self._tf = _Layout(fields, constants)
        frames = np.void(_string(world) + _string(parent))
        self._gt = _Layout(
            [
                ("seq", _U4),
                ("stamp", _U4, (2,)),
                ("frames", frames.dtype),
                ("pose", _F8, (7,)),
                ("pose_cov", _F8, (36,)),
                ("twist", _F8, (6,)),
                ("twist_cov", _F8, (36,)),
            ],
            {"frames": frames},
        )

        self._nj, self._nb = n, 1 + self._k
        lib, self.engine = open_helper(C_SOURCE, native)
        """``"C"`` or ``"Python (<why>)"``: what :meth:`blocks` runs."""
        self._fn = None
        if lib is not None:
            self._fn = fn = lib.fb_blocks
            p, i, q = ctypes.c_void_p, ctypes.c_int, ctypes.c_int64
            fn.restype, fn.argtypes = i, [p, i, i, i, i, q, *[p, p, i, p] * 3, p]
            offsets = {
                "gt": ("stamp", "pose", "twist"),
                "js": ("stamp", "q", "qd"),
                "tf": [f"{f}{i}" for i in range(self._k) for f in ("stamp", "pose")],
            }
            self._c = {}  # layout -> (record size, template's and offsets' addresses)
            self._keep = []  # the arrays those addresses are in
            for key, names in offsets.items():
                tmpl = getattr(self, "_" + key).template
                fields = tmpl.dtype.fields
                at = np.array([fields[name][1] for name in names], np.int32)
                self._keep += [tmpl, at]
                self._c[key] = (tmpl.dtype.itemsize, address(tmpl.view(np.uint8)), address(at))

    def blocks(self, sampler, period_us: int, gt: bool, js: bool, tf: bool) -> TickBlocks:
        """The blocks of ``sampler``'s samples (a :class:`~amr_twin.ros.ros_state.StateSampler`):
        the ground truths of all if ``gt``, the joint states if ``js`` and link transforms if
        ``tf`` of those at multiples of ``period_us``."""
        table = sampler.table
        width = 1 + 2 * self._nj + 6 + 7 * self._nb
        if self._fn is None or not len(table) or table.shape[1] != width:
            return self._blocks_python(sampler, period_us, gt, js, tf)
        table = c_array(table, np.float64)
        n, args, out = len(table), [], {}
        for key, wanted in (("gt", gt), ("js", js), ("tf", tf)):
            size, tmpl, at = self._c[key]
            buf = out[key] = np.empty(n * size if wanted else 0, np.uint8)
            args += [address(buf) if wanted else None, tmpl, size, at]
        kept = np.empty(n, np.int64)
        m = self._fn(address(table), n, width, self._nj, self._nb, period_us, *args, address(kept))
        kept_us = kept[:m].tolist()
        return TickBlocks(
            table[:, 0].astype(np.int64).tolist() if gt else [],
            out["gt"].tobytes() if gt else None,
            kept_us,
            out["js"][: m * self._c["js"][0]].tobytes() if js else None,
            out["tf"][: m * self._c["tf"][0]].tobytes() if tf else None,
        )

    def _blocks_python(self, sampler, period_us: int, gt: bool, js: bool, tf: bool) -> TickBlocks:
        a = sampler.arrays(0 if gt else period_us, gt)
        t = a["t_us"]
        gt_us, gt_block = [], None
        if gt:
            gt_us = t.tolist()
            gt_block = self.ground_truth(t, a["pos"], a["quat"], a["v_body"], a["w_body"])
            keep = t % period_us == 0
            t, a = t[keep], {key: a[key][keep] for key in ("q", "qd", "link_pos", "link_quat")}
        return TickBlocks(
            gt_us,
            gt_block,
            t.tolist(),
            self.joint_states(t, a["q"], a["qd"]) if js else None,
            self.link_transforms(t, a["link_pos"], a["link_quat"]) if tf else None,
        )

    def joint_states(self, t_us, q, qd) -> bytes:
        """Positions ``q`` and velocities ``qd`` (m, n) at instants ``t_us`` (m,); no efforts."""
        rec = self._js.records(len(t_us))
        rec["stamp"][:, 0], rec["stamp"][:, 1] = _stamps(t_us)
        rec["q"], rec["qd"] = q, qd
        return rec.tobytes()

    def link_transforms(self, t_us, link_pos, link_quat) -> bytes:
        """Each link's position (m, k, 3) and orientation (m, k, 4) w, x, y, z relative to the
        parent, at ``t_us``."""
        rec = self._tf.records(len(t_us))
        sec, nsec = _stamps(t_us)
        pos, quat = np.asarray(link_pos, float), np.asarray(link_quat, float)
        for i in range(self._k):
            rec[f"stamp{i}"][:, 1], rec[f"stamp{i}"][:, 2] = sec, nsec
            pose = rec[f"pose{i}"]
            pose[:, :3], pose[:, 3:6], pose[:, 6] = pos[:, i], quat[:, i, 1:], quat[:, i, 0]
        return rec.tobytes()

    def ground_truth(self, t_us, pos, quat, v_body, w_body) -> bytes:
        """``nav_msgs/Odometry`` of the true pose, ``world -> base_link``: positions (m, 3),
        orientations (m, 4) w, x, y, z, the twist in ``base_link`` (m, 3) and (m, 3), zero
        covariances, at ``t_us`` (m,)."""
        rec = self._gt.records(len(t_us))
        rec["stamp"][:, 0], rec["stamp"][:, 1] = _stamps(t_us)
        quat = np.asarray(quat, float)
        pose = rec["pose"]
        pose[:, :3], pose[:, 3:6], pose[:, 6] = pos, quat[:, 1:], quat[:, 0]
        rec["twist"][:, :3], rec["twist"][:, 3:] = v_body, w_body
        return rec.tobytes()


_CLOCK = _Layout([("stamp", _U4, (2,))])
_ROWS: dict[int, _Layout] = {}  # by the row's width


def clock_block(t_us) -> bytes:
    """``rosgraph_msgs/Clock`` at each of the instants ``t_us`` (us)."""
    rec = _CLOCK.records(len(t_us))
    rec["stamp"][:, 0], rec["stamp"][:, 1] = _stamps(t_us)
    return rec.tobytes()


def float64_rows_block(rows) -> bytes:
    """``std_msgs/Float64MultiArray`` with no dimensions of each row of ``rows`` (m, n) floats."""
    rows = np.asarray(rows, float)
    n = rows.shape[1]
    layout = _ROWS.get(n)
    if layout is None:
        layout = _ROWS[n] = _Layout([("head", _U4, (3,)), ("data", _F8, (n,))], {"head": (0, 0, n)})
    rec = layout.records(len(rows))
    rec["data"] = rows
    return rec.tobytes()


BATTERY_RECORD = _Layout(
    [
        ("seq", _U4),
        ("stamp", _U4, (2,)),
        ("frame_id", _U4),
        ("values", "<f4", (7,)),
        ("enums", "u1", (3,)),
        ("present", "u1"),
        ("tail", _U4, (4,)),
    ],
    {"present": 1},
)


def battery_block(t_us, voltage_v, current_a, charge_ah, capacity_ah: float, soc) -> bytes:
    """``sensor_msgs/BatteryState`` at each of the instants ``t_us`` (m,): voltage, current
    (negative discharging), charge (m,) and ``soc`` (m,) as ``percentage`` (0 to 1); capacity and
    design capacity ``capacity_ah``; present, no temperature (0), statuses unknown, no cells,
    location or serial number."""
    rec = BATTERY_RECORD.records(len(t_us))
    rec["stamp"][:, 0], rec["stamp"][:, 1] = _stamps(t_us)
    values = rec["values"]
    values[:, 0], values[:, 2], values[:, 3] = voltage_v, current_a, charge_ah
    values[:, 4] = values[:, 5] = capacity_ah
    values[:, 6] = soc
    return rec.tobytes()
