"""The tf buffer: the latest transform of each child frame, and lookups along the tree.

Frames follow REP-105: ``odom -> base_link -> {laser, imu_link, uwb_tag}``, and
``map -> uwb_anchor_<i>``. Translations are in m, rotations quaternions (x, y, z, w); a
lookup composes the stored transforms up to the frames' common ancestor and back, as
tf2's ``lookupTransform`` (latest transforms only, no time travel). The bus keeps one
buffer (:attr:`amr_twin.ros.bus.Bus.tf`) and fills it through ``Bus.send_transform``.
"""

from __future__ import annotations

from amr_twin.ros.geometry_messages import Quaternion, Transform, TransformStamped, Vector3

ODOM_FRAME = "odom"
BASE_FRAME = "base_link"
LASER_FRAME = "laser"
IMU_FRAME = "imu_link"


class TransformError(LookupError):
    """Two frames are not connected in the tf buffer."""


def _qmul(a: Quaternion, b: Quaternion) -> Quaternion:
    return Quaternion(
        a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
        a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
        a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w,
        a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
    )


def _rotate(q: Quaternion, v: Vector3) -> Vector3:
    p = _qmul(_qmul(q, Quaternion(v.x, v.y, v.z, 0.0)), Quaternion(-q.x, -q.y, -q.z, q.w))
    return Vector3(p.x, p.y, p.z)


def _compose(a: Transform, b: Transform) -> Transform:
    """Transform ``a * b`` (apply ``b`` first, then ``a``)."""
    t = _rotate(a.rotation, b.translation)
    return Transform(
        Vector3(a.translation.x + t.x, a.translation.y + t.y, a.translation.z + t.z),
        _qmul(a.rotation, b.rotation),
    )


def _inverse(a: Transform) -> Transform:
    qi = Quaternion(-a.rotation.x, -a.rotation.y, -a.rotation.z, a.rotation.w)
    t = _rotate(qi, a.translation)
    return Transform(Vector3(-t.x, -t.y, -t.z), qi)


class TfBuffer:
    """The latest transform of each child frame, and lookups along the tree."""

    def __init__(self) -> None:
        self._edges: dict[str, TransformStamped] = {}

    def set_transform(self, ts: TransformStamped) -> None:
        """Store ``ts`` as the current pose of ``ts.child_frame_id`` in its parent."""
        self._edges[ts.child_frame_id] = ts

    def frames(self) -> set[str]:
        """Every frame named by a stored transform."""
        return set(self._edges) | {ts.header.frame_id for ts in self._edges.values()}

    def _chain(self, frame: str) -> list[str]:
        chain = [frame]
        while chain[-1] in self._edges and len(chain) <= len(self._edges):
            chain.append(self._edges[chain[-1]].header.frame_id)
        return chain

    def _to_ancestor(self, frame: str, ancestor: str) -> Transform:
        result = Transform()
        while frame != ancestor:
            edge = self._edges[frame]
            result = _compose(edge.transform, result)
            frame = edge.header.frame_id
        return result

    def lookup_transform(self, target_frame: str, source_frame: str) -> Transform:
        """Pose of ``source_frame`` expressed in ``target_frame`` (tf2 convention).

        Raises
        ------
        TransformError
            The frames are not connected.
        """
        up_source = self._chain(source_frame)
        up_target = self._chain(target_frame)
        common = next((f for f in up_source if f in up_target), None)
        if common is None:
            raise TransformError(f"no transform between {target_frame!r} and {source_frame!r}")
        source_in_common = self._to_ancestor(source_frame, common)
        target_in_common = self._to_ancestor(target_frame, common)
        return _compose(_inverse(target_in_common), source_in_common)

    def yaw_rad(self, target_frame: str, source_frame: str) -> float:
        """Heading of ``source_frame`` in ``target_frame``, radians."""
        return self.lookup_transform(target_frame, source_frame).rotation.yaw_rad()
