"""The EKF's inputs made ready to fuse: the twist of an odometry message, the gyro's rest
calibration of its bias and the UWB anchors' geometry (the node: :mod:`amr_twin.estimation.ekf`).

Reasons and measurements: docs/explanation/fusion.md#amr_twinestimationekf."""

from __future__ import annotations

import numpy as np

from amr_twin.estimation.ekf_filter import UnicycleEkf
from amr_twin.estimation.ekf_model import BG, pose_difference_twist, range_model
from amr_twin.model.config_estimation import EkfCfg
from amr_twin.model.config_sensors import UwbCfg
from amr_twin.ros.geometry_messages import Odometry
from amr_twin.sensors.uwb import anchor_index


class OdometryTwist:
    """``(v_m_s, w_rad_s)`` of odometry messages: each one's twist, or, ``differential``
    (``ekf.odom_differential``), its pose differentiated against the previous message's."""

    def __init__(self, differential: bool):
        self.differential = differential
        self._prev: tuple[float, float, float, float] | None = None

    def __call__(self, msg: Odometry) -> tuple[float, float] | None:
        """The twist of ``msg``; None for the first message and a repeated stamp (differential)."""
        if not self.differential:
            return float(msg.twist.twist.linear.x), float(msg.twist.twist.angular.z)
        t_s, p = msg.header.stamp.to_sec(), msg.pose.pose
        now = (t_s, p.position.x, p.position.y, p.orientation.yaw_rad())
        prev, self._prev = self._prev, now
        if prev is None or now[0] <= prev[0]:
            return None
        return pose_difference_twist(prev, now)


class GyroRestCalibration:
    """The gyro's bias: the mean of its z rate over the first ``imu_rest_calibration_s`` at rest
    (both wheels' speeds, ``half_track_m`` m off the middle, within ``rest_speed_m_s``)."""

    def __init__(self, cfg: EkfCfg, half_track_m: float):
        self.cfg, self.half_track_m = cfg, half_track_m
        self.done = cfg.imu_rest_calibration_s <= 0.0
        self._t0_s: float | None = None
        self._samples: list[float] = []

    def at_rest(self, twist: tuple[float, float]) -> bool:
        """Whether the twist ``(v_m_s, w_rad_s)`` is at rest."""
        v, w = twist
        return abs(v) <= self.cfg.rest_speed_m_s and abs(w) * self.half_track_m <= (
            self.cfg.rest_speed_m_s
        )

    def take(self, t_s: float, gz_rad_s: float, twist: tuple[float, float]) -> bool:
        """Keep the rate ``gz_rad_s`` at ``t_s`` s for the mean while in the calibration time and at
        rest (``twist``, the last odometry's); False once it is over."""
        if self._t0_s is None:
            self._t0_s = t_s
        if t_s - self._t0_s < self.cfg.imu_rest_calibration_s and self.at_rest(twist):
            self._samples.append(gz_rad_s)
            return True
        return False

    def finish(self, f: UnicycleEkf) -> None:
        """Put the mean (if any rate was kept) into the filter's bias state and its variance."""
        if self._samples:
            f.x[BG, 0] = float(np.mean(self._samples))
            f.P[BG, :] = 0.0
            f.P[:, BG] = 0.0
            f.P[BG, BG] = self.cfg.gyro_w_sigma_rad_s**2 / len(self._samples)
        self.done = True


class AnchorGeometry:
    """The UWB anchors ``anchors_xy_m`` (M, 2) in the output frame, the tag ``tag_xy_m`` (2,) in
    ``base_link`` and the anchors' height over the tag ``dz_m``, m; each from the arguments, else
    ``uwb``'s (anchors needed with ``use_uwb``; the tag at the origin and 2D ranges without)."""

    def __init__(
        self,
        *,
        use_uwb: bool,
        anchors_xy_m: np.ndarray | None = None,
        uwb: UwbCfg | None = None,
        anchor_z_m: float | None = None,
        tag_pos_m=None,
    ):
        if anchors_xy_m is None and uwb is not None:
            anchors_xy_m = uwb.anchors_xy_m
        tag = (
            tag_pos_m
            if tag_pos_m is not None
            else (uwb.tag_pos_m if uwb is not None else (0.0, 0.0, 0.0))
        )
        self.tag_xy_m = np.asarray(tag, dtype=np.float64)[:2]
        z_anchor = (
            anchor_z_m
            if anchor_z_m is not None
            else (uwb.anchor_z_m if uwb is not None else tag[2])
        )
        self.dz_m = float(z_anchor) - float(tag[2])
        self.anchors_xy_m = None
        if use_uwb:
            if anchors_xy_m is None:
                raise ValueError("anchors_xy_m: needed when use_uwb is True (or pass uwb=cfg.uwb)")
            self.anchors_xy_m = np.asarray(anchors_xy_m, dtype=np.float64).reshape(-1, 2)

    def index(self, frame_id: str) -> int:
        """The anchor of a range's ``header.frame_id``; ValueError for one not among them."""
        index = anchor_index(frame_id)
        if index >= self.anchors_xy_m.shape[0]:
            raise ValueError(
                f"header.frame_id: anchor {index} not in [0, {self.anchors_xy_m.shape[0] - 1}]"
            )
        return index

    def model(self, x: np.ndarray, index: int) -> tuple[float, np.ndarray]:
        """Predicted range to anchor ``index`` (m) from the state ``x`` (6,) and its Jacobian,
        shape (1, 6) (:func:`~amr_twin.estimation.ekf_model.range_model`)."""
        return range_model(x, self.anchors_xy_m[index], self.tag_xy_m, self.dz_m)
