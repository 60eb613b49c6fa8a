"""EKF fusing wheel odometry, the gyro and UWB ranges, after robot_localization's ekf_node.

The thesis (§6.2.1, figs. 6.5 to 6.7) fuses odometry with the IMU and UWB in an
extended Kalman filter; this node does it as robot_localization's ``ekf_node`` in
``two_d_mode`` with filterpy's :class:`~filterpy.kalman.ExtendedKalmanFilter`.

Reasons and measurements: docs/explanation/fusion.md#amr_twinestimationekf."""

from __future__ import annotations

import bisect
import math

import numpy as np

from amr_twin.analysis import se2
from amr_twin.ros.bus import Bus
from amr_twin.ros.tf_buffer import BASE_FRAME, ODOM_FRAME
from amr_twin.model.config_estimation import EkfCfg
from amr_twin.model.config_sensors import UwbCfg
from amr_twin.ros.geometry_messages import (
    Odometry,
    Point,
    Pose,
    PoseWithCovariance,
    PoseWithCovarianceStamped,
    Quaternion,
    Twist,
    TwistWithCovariance,
    Vector3,
)
from amr_twin.ros.messages import Header
from amr_twin.ros.sensor_messages import Imu, Range

from amr_twin.estimation.ekf_filter import initial_filter
from amr_twin.estimation.ekf_inputs import AnchorGeometry, GyroRestCalibration, OdometryTwist
from amr_twin.estimation.ekf_model import (
    V,
    W,
    X,
    Y,
    YAW,
    gyro_model,
    linear_model,
    odometry_covariances,
    process_noise,
    transition_jacobian,
)

MAP_FRAME = "map"
TOPIC = "odometry/filtered"
POSE_TOPIC = "map_match/pose"
"""The EKF's pose input, where the navigator publishes the matched pose
(``geometry_msgs/PoseWithCovarianceStamped`` in ``map``; AMCL's ``amcl_pose``, which
robot_localization fuses as ``pose0``)."""
_POSE_ROWS = np.ix_([0, 1, 5], [0, 1, 5])
"""x, y and yaw in a ``PoseWithCovariance``'s 6 x 6 covariance."""


class EkfNode:
    """Planar EKF over odometry twist, gyro z rate and UWB ranges.

    Parameters
    ----------
    cfg : EkfCfg
        Noise, gate and calibration settings (``ekf:`` section).
    wheel_separation_m : float
        ``wheel.separation_m``: half of it turns a yaw rate into a wheel speed for the rest test.
    use_odom, use_imu, use_uwb : bool
        Which measurements are fused (the others are ignored).
    anchors_xy_m : ndarray, shape (M, 2), optional
        Anchor positions in the world frame, m (default: ``uwb``'s).
    initial_pose : (x_m, y_m, yaw_rad)
        Start pose in the output frame.
    bus : Bus, optional
        Subscribe to the inputs and publish ``odometry/filtered``.
    uwb : UwbCfg, optional
        Anchors, anchor height and tag position in one (``uwb:`` section).
    anchor_z_m : float, optional
        Anchor height, m (default: ``uwb``'s, else the tag height: 2D ranges).
    tag_pos_m : sequence of 3 float, optional
        Tag position in ``base_link``, m (default: ``uwb``'s, else the origin).
    """

    def __init__(
        self,
        cfg: EkfCfg,
        *,
        wheel_separation_m: float,
        use_odom: bool = True,
        use_imu: bool,
        use_uwb: bool,
        anchors_xy_m: np.ndarray | None = None,
        initial_pose=(0.0, 0.0, 0.0),
        bus: Bus | None = None,
        uwb: UwbCfg | None = None,
        anchor_z_m: float | None = None,
        tag_pos_m=None,
    ):
        if not (use_odom or use_imu or use_uwb):
            raise ValueError("use_odom, use_imu, use_uwb: at least one must be True")
        pose = np.asarray(initial_pose, dtype=np.float64).ravel()
        if pose.shape != (3,) or not np.all(np.isfinite(pose)):
            raise ValueError(
                f"initial_pose: expected 3 finite numbers (x_m, y_m, yaw_rad), got {initial_pose!r}"
            )
        self.cfg, self.use_odom, self.use_imu, self.use_uwb = cfg, use_odom, use_imu, use_uwb
        self.anchors = AnchorGeometry(
            use_uwb=use_uwb,
            anchors_xy_m=anchors_xy_m,
            uwb=uwb,
            anchor_z_m=anchor_z_m,
            tag_pos_m=tag_pos_m,
        )
        self.frame_id = MAP_FRAME if use_uwb else ODOM_FRAME

        self.filter = initial_filter(cfg, pose)
        self._odom_h = linear_model([V, W])
        self._odom_R = np.diag([cfg.odom_v_sigma_m_s**2, cfg.odom_w_sigma_rad_s**2])
        self._gyro_h = gyro_model()
        self._gyro_R = np.array([[cfg.gyro_w_sigma_rad_s**2]])
        self._uwb_R = np.array([[cfg.uwb_range_sigma_m**2]])
        self._pose_h = linear_model([X, Y, YAW])

        self.t_s: float | None = None
        self._t_hist: list[float] = []
        self._pose_hist: list[tuple[float, float, float]] = []
        self._last_twist = (0.0, 0.0)
        self._odom_twist = OdometryTwist(cfg.odom_differential)
        self.gyro_rest = GyroRestCalibration(cfg, 0.5 * float(wheel_separation_m))
        """The gyro bias' rest calibration (``half_track_m``: half the wheels' separation)."""
        self.late_messages = 0
        self.rejected_ranges = 0
        self.fused = {"odom": 0, "imu": 0, "uwb": 0, "pose": 0}
        self._seq = 0
        self._pub = None
        if bus is not None:
            self._pub = bus.advertise(TOPIC, Odometry)
            if use_odom:
                bus.subscribe("odom", self.on_odom)
            if use_imu:
                bus.subscribe("imu/data_raw", self.on_imu)
            if use_uwb:
                bus.subscribe("uwb/range", self.on_range)
                bus.subscribe(POSE_TOPIC, self.on_pose)

    # -- filter steps ---------------------------------------------------------------
    def _predict_to(self, t_s: float) -> None:
        if self.t_s is None:
            self.t_s = t_s
            return
        dt = t_s - self.t_s
        if dt < 0.0:
            self.late_messages += 1
            return
        if dt == 0.0:
            return
        f = self.filter
        x = f.x[:, 0]
        f.F, f.Q, f.dt_s = transition_jacobian(x, dt), process_noise(x, dt, self.cfg), dt
        f.predict()
        self.t_s = t_s

    def _record(self) -> None:
        x = self.filter.x[:, 0]
        self._t_hist.append(self.t_s)
        self._pose_hist.append((float(x[X]), float(x[Y]), float(x[YAW])))

    # -- inputs -------------------------------------------------------------------------
    def on_odom(self, msg: Odometry) -> None:
        """Fuse the forward speed and yaw rate of a wheel odometry message."""
        twist = self._odom_twist(msg)
        if twist is None:
            return
        v, w = twist
        self._last_twist = (v, w)
        if not self.use_odom:
            return
        self._predict_to(msg.header.stamp.to_sec())
        HJ, Hx, _ = self._odom_h
        self.filter.update(np.array([[v], [w]]), HJ, Hx, R=self._odom_R)
        self.fused["odom"] += 1
        self._record()
        self._publish(msg.header.stamp)

    def on_imu(self, msg: Imu) -> None:
        """Fuse the gyro's z rate (after the rest calibration of its bias)."""
        if not self.use_imu:
            return
        t_s, gz = msg.header.stamp.to_sec(), float(msg.angular_velocity.z)
        if not self.gyro_rest.done:
            if self.gyro_rest.take(t_s, gz, self._last_twist):
                return
            self.gyro_rest.finish(self.filter)
        self._predict_to(t_s)
        HJ, Hx = self._gyro_h
        self.filter.update(np.array([[gz]]), HJ, Hx, R=self._gyro_R)
        self.fused["imu"] += 1
        self._record()
        if not self.use_odom:
            self._publish(msg.header.stamp)

    def on_range(self, msg: Range) -> None:
        """Fuse one UWB range, unless its Mahalanobis distance exceeds the gate."""
        if not self.use_uwb:
            return
        index = self.anchors.index(msg.header.frame_id)
        z = float(msg.range)
        if not (msg.min_range <= z <= msg.max_range) or not math.isfinite(z):
            return
        self._predict_to(msg.header.stamp.to_sec())
        f = self.filter
        r, H = self.anchors.model(f.x[:, 0], index)
        S = float((H @ f.P @ H.T)[0, 0]) + self._uwb_R[0, 0]
        if abs(z - r) > self.cfg.mahalanobis_gate * math.sqrt(S):
            self.rejected_ranges += 1
            return
        f.update(
            np.array([[z]]),
            lambda x: self.anchors.model(x[:, 0], index)[1],
            lambda x: np.array([[self.anchors.model(x[:, 0], index)[0]]]),
            R=self._uwb_R,
        )
        self.fused["uwb"] += 1
        self._record()
        if not self.use_odom:
            self._publish(msg.header.stamp)

    def on_pose(self, msg: PoseWithCovarianceStamped) -> None:
        """Fuse a pose in ``map`` (x, y, yaw) with the message's covariance of them, then publish.

        A pose of an instant the filter has passed (the navigator matched the pose it was given) is
        carried to the filter's time by the filter's own motion since, and the result published at
        the pose's stamp, carried back: the receiver sees the jump the fusion made at the instant it
        knows."""
        if msg.header.frame_id != MAP_FRAME:
            raise ValueError(
                f"{POSE_TOPIC}: header.frame_id must be {MAP_FRAME!r}, got {msg.header.frame_id!r}"
            )
        p = msg.pose.pose
        z = np.array([p.position.x, p.position.y, p.orientation.yaw_rad()])
        R = np.asarray(msg.pose.covariance, dtype=np.float64).reshape(6, 6)[_POSE_ROWS]
        t_s = msg.header.stamp.to_sec()
        k = bisect.bisect_right(self._t_hist, t_s) - 1
        since = None
        if self.t_s is not None and t_s < self.t_s and k >= 0:
            since = se2.between(
                self._pose_hist[k], self.filter.x[:3, 0]
            )  # the motion from then to now
            z = se2.compose(z, since)
        else:
            self._predict_to(t_s)
        HJ, Hx, _ = self._pose_h
        yaw = float(self.filter.x[YAW, 0])
        z[2] = yaw + math.remainder(z[2] - yaw, math.tau)  # the innovation's yaw in (-pi, pi]
        self.filter.update(z.reshape(3, 1), HJ, Hx, R=R)
        self.fused["pose"] += 1
        self._record()
        if self._pub is not None:
            then = None if since is None else se2.compose(self.filter.x[:3, 0], se2.inverse(since))
            self._pub.publish(self.message(msg.header.stamp, pose=then))

    # -- outputs ------------------------------------------------------------------------
    @property
    def state(self) -> np.ndarray:
        """Current state ``[x_m, y_m, yaw_rad, v_m_s, w_rad_s, gyro_bias_rad_s]``, shape (6,)."""
        return self.filter.x[:, 0].copy()

    def history(self) -> tuple[np.ndarray, np.ndarray]:
        """Stamps ``t_s`` (N,) and poses (N, 3) ``[x_m, y_m, yaw_rad]`` after every update.

        The yaw is wrapped to (-pi, pi].
        """
        t = np.asarray(self._t_hist, dtype=np.float64)
        pose = np.asarray(self._pose_hist, dtype=np.float64).reshape(-1, 3)
        pose[:, 2] = np.arctan2(np.sin(pose[:, 2]), np.cos(pose[:, 2]))
        return t, pose

    def message(self, stamp, pose=None) -> Odometry:
        """The current estimate as ``nav_msgs/Odometry`` (frame ``odom`` or ``map``, child
        ``base_link``); ``pose`` (3,) in place of the state's x, y, yaw."""
        x = self.filter.x[:, 0]
        px, py, pyaw = (x[X], x[Y], x[YAW]) if pose is None else pose
        pose_cov, twist_cov = odometry_covariances(self.filter.P)
        self._seq += 1
        return Odometry(
            header=Header(self._seq, stamp, self.frame_id),
            child_frame_id=BASE_FRAME,
            pose=PoseWithCovariance(
                Pose(Point(float(px), float(py), 0.0), Quaternion.from_yaw(float(pyaw))), pose_cov
            ),
            twist=TwistWithCovariance(
                Twist(Vector3(float(x[V]), 0.0, 0.0), Vector3(0.0, 0.0, float(x[W]))), twist_cov
            ),
        )

    def _publish(self, stamp) -> None:
        if self._pub is not None:
            self._pub.publish(self.message(stamp))
