"""The metrics of a navigation episode, as BARN, arena-bench and MRPB report them, and their
summary.

Per episode (:func:`measure`):

- ``success``: the goal reached without a collision, judged by the TRUE pose at the end: within the
goal
  checker's tolerances (xy and yaw) of the goal, whatever the navigator's estimate said
  (:mod:`amr_twin.navigation.goal_truth`); ``final_error_*``: the truth's and the estimate's
  distance and heading error from the goal at the end;
- ``collisions``: contacts of the robot's body with the world (amr_twin/sim/collisions.py);
- ``time_s``: from the navigator's start to the goal (or to the end);
- ``barn_score``: ``success * OT / clip(AT, 2 OT, 8 OT)`` with ``OT`` the optimal length over the
  top speed and ``AT`` the time (BARN challenge; 0.5 at best);
- ``travelled_m``, ``optimal_m`` (the visibility graph's shortest path,
  :mod:`.optimal`), their ratio;
- ``min_clearance_m``: the least distance from the true footprint (the rectangle at the true pose,
  10 Hz) to any obstacle of the true world, unmapped ones included; ``min_person_m``: to the person;
- ``plan_ms`` (each plan's CPU), ``controller_ms`` (each control cycle's CPU): percentiles;
- ``recoveries`` and ``recoveries_per_100m``;
- ``w_sign_changes_last_m``: sign changes of the commanded yaw rate (beyond 0.02 rad/s) over the
  last metre of travel, the oscillation nav2 users report when turning to the final heading.
"""

from __future__ import annotations

import math

import numpy as np

W_DEADBAND_RAD_S = 0.02
PERSON_HALF_M = (0.15, 0.225)
"""Half the depth and width of a walking person's body (amr.yaml's actors.person torso, 0.25 x 0.45
m, legs within)."""


def footprint_clearance_m(poses: np.ndarray, footprint, boxes) -> np.ndarray:
    """Least distance (n,) from the footprint at each pose (n, 3) to ``boxes`` (their footprints),
    m."""
    from amr_twin.model.world_geometry import Footprints, distance_to_boxes_m
    from amr_twin.navigation.kinematics import to_map

    if len(boxes.names) == 0:
        return np.full(len(poses), np.inf)
    fp = Footprints(boxes.centre_xy_m, boxes.half_xy_m, boxes.yaw_rad, boxes.names)
    outline = footprint.outline_xy_m(0.05)
    pts = to_map(poses, outline)  # (n, P, 2)
    d = distance_to_boxes_m(pts.reshape(-1, 2), fp).reshape(len(poses), -1)
    inside = np.array([footprint.contains(_to_base(p, boxes.centre_xy_m)).any() for p in poses])
    out = d.min(1)
    out[inside] = 0.0
    return out


def world_obstacle_boxes(cfg, world: str):
    """The footprints of the world's obstacles the robot can hit (floor to its top; a ROS map
    world's extruded walls), as :func:`footprint_clearance_m` takes them."""
    import mujoco

    from amr_twin.model.occupancy_map import world_xml
    from amr_twin.model.worlds import world_path
    from amr_twin.navigation.stack import robot_top_m
    from amr_twin.navigation.static_map import obstacle_boxes

    model = (
        mujoco.MjModel.from_xml_string(world_xml(world))
        if str(world).endswith(".yaml")  # a ROS map world
        else mujoco.MjModel.from_xml_path(str(world_path(world)))
    )
    return obstacle_boxes(model, 0.005, robot_top_m(cfg))


def _to_base(pose, xy):
    c, s = math.cos(pose[2]), math.sin(pose[2])
    d = np.asarray(xy) - pose[:2]
    return np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])


def _sign_changes(w: np.ndarray) -> int:
    s = np.sign(np.where(np.abs(w) > W_DEADBAND_RAD_S, w, 0.0))
    s = s[s != 0]
    return int((s[1:] != s[:-1]).sum())


def measure(cfg, world: str, episode, map_kind: str, run) -> dict:
    """The metrics of one finished episode (module docstring), with its trajectory at 5 Hz for the
    plots."""
    from amr_twin.experiments.navigation.optimal import VisibilityGraph
    from amr_twin.navigation.footprint import robot_footprint
    from amr_twin.navigation.kinematics import Limits
    from amr_twin.model.world_geometry import Footprints

    out = run.outcomes[0]
    footprint = robot_footprint(cfg)
    world_boxes = world_obstacle_boxes(cfg, world)
    ob = episode.obstacle
    extra = (
        Footprints(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0), ())
        if ob is None
        else Footprints(
            np.array([[ob.x_m, ob.y_m]]),
            np.array([[ob.size_m[0] / 2, ob.size_m[1] / 2]]),
            np.array([ob.yaw_rad]),
            (ob.name,),
        )
    )
    boxes = Footprints(
        np.vstack([world_boxes.centre_xy_m, extra.centre_xy_m]),
        np.vstack([world_boxes.half_xy_m, extra.half_xy_m]),
        np.concatenate([world_boxes.yaw_rad, extra.yaw_rad]),
        world_boxes.names + extra.names,
    )
    c = boxes.centre_xy_m
    lo, hi = c.min(0) - 2.0, c.max(0) + 2.0
    optimal = VisibilityGraph(
        boxes, footprint.inscribed_radius_m, (lo[0], lo[1], hi[0], hi[1])
    ).length_m(episode.start[:2], episode.goal[:2])
    t, pose = run.t_s, run.pose_true
    t0 = out.t_start_s if math.isfinite(out.t_start_s) else t[0]
    t1 = out.t_end_s if math.isfinite(out.t_end_s) else t[-1]
    moving = (t >= t0) & (t <= t1)
    xy = pose[moving, :2]
    step = np.hypot(*np.diff(xy, axis=0).T) if len(xy) > 1 else np.zeros(0)
    travelled = float(step.sum())
    every = pose[moving][::10]
    clearance = footprint_clearance_m(every, footprint, boxes)
    person = (
        footprint_clearance_m(every, footprint, extra)
        if ob is not None and ob.name == "person"
        else None
    )
    if (
        episode.actor is not None and run.actor_poses
    ):  # a walking person: their body (0.45 x 0.3 m) at 10 Hz
        ta = np.array([a[0] for a in run.actor_poses])
        keep = (ta >= t0) & (ta <= t1)
        body = np.array([a[1][0] for a in run.actor_poses])[keep]
        robot = np.column_stack(
            [np.interp(ta[keep], t, pose[:, k]) for k in range(2)]
            + [np.interp(ta[keep], t, np.unwrap(pose[:, 2]))]
        )
        person = np.array(
            [
                footprint_clearance_m(
                    robot[k : k + 1],
                    footprint,
                    Footprints(
                        body[k : k + 1, :2],
                        np.array([[PERSON_HALF_M[0], PERSON_HALF_M[1]]]),
                        body[k : k + 1, 2],
                        ("person",),
                    ),
                )[0]
                for k in range(len(robot))
            ]
        )
    tol = cfg.navigation.navigator
    final = run.final_errors[0]
    reached = out.status == "succeeded" and final.within(tol.xy_tolerance_m, tol.yaw_tolerance_rad)
    success = reached and not run.collisions
    time_s = float(t1 - t0)
    ot = optimal / Limits().max_v_m_s
    barn = float(success) * ot / min(max(time_s, 2 * ot), 8 * ot) if math.isfinite(ot) else 0.0
    remaining = travelled - np.concatenate([[0.0], np.cumsum(step)])
    last_t = t[moving][remaining <= 1.0][0] if len(remaining) else t1
    cmd = run.commands
    w_last = cmd[(cmd[:, 0] >= last_t) & (cmd[:, 0] <= t1), 2] if len(cmd) else np.zeros(0)
    plan_ms = 1e3 * np.asarray(out.plan_cpu_s, float)
    ctl_ms = 1e3 * np.asarray(run.controller_cpu_s, float)
    sub = pose[::20]  # 5 Hz for the plots
    return {
        "index": episode.index,
        "seed": episode.seed,
        "scenario": episode.scenario,
        "map": map_kind,
        "start": list(episode.start),
        "goal": list(episode.goal),
        "obstacle": None
        if ob is None
        else {
            "kind": ob.name,
            "x_m": ob.x_m,
            "y_m": ob.y_m,
            "size_m": list(ob.size_m),
            "yaw_rad": ob.yaw_rad,
        },
        "actor": None
        if episode.actor is None
        else {
            "kind": episode.actor.kind,
            "start_s": episode.actor.start_s,
            "waypoints_xy_m": [list(p) for p in episode.actor.waypoints_xy_m],
        },
        "status": out.status,
        "reason": out.reason,
        "success": bool(success),
        "collisions": len(run.collisions),
        "collided_with": sorted({col.get("hit", "?") for col in run.collisions}),
        "final_error_true_m": final.true_xy_m,
        "final_error_estimate_m": final.estimate_xy_m,
        "final_error_true_yaw_rad": final.true_yaw_rad,
        "final_error_estimate_yaw_rad": final.estimate_yaw_rad,
        "time_s": time_s,
        "barn_score": barn,
        "travelled_m": travelled,
        "optimal_m": optimal,
        "travelled_over_optimal": travelled / optimal if reached and optimal > 0 else None,
        "min_clearance_m": float(clearance.min()) if len(clearance) else None,
        "min_person_m": None if person is None or not len(person) else float(person.min()),
        "plan_ms": plan_ms.tolist(),
        "controller_ms_p50": float(np.median(ctl_ms)) if len(ctl_ms) else None,
        "controller_ms_p99": float(np.percentile(ctl_ms, 99)) if len(ctl_ms) else None,
        "controller_ms": ctl_ms[::4].tolist(),
        "recoveries": [r[1] for r in out.recoveries],
        "recoveries_per_100m": 100.0 * len(out.recoveries) / max(travelled, 1.0),
        "w_sign_changes_last_m": _sign_changes(w_last),
        "monitor": run.monitor_actions,
        "sim_s": run.sim_s,
        "wall_s": run.wall_s,
        "trajectory": sub[:, :2].round(3).tolist(),
    }


def _pct(values, q):
    values = [v for v in values if v is not None]
    return float(np.percentile(values, q)) if values else None


def summary(rows: list[dict]) -> dict:
    """Each metric by map and scenario (``with_people`` pools the person and pallet-jack
    episodes)."""
    out = {}
    for map_kind in sorted({r["map"] for r in rows}):
        for group, kinds in (
            ("all", None),
            ("clear", ("clear",)),
            ("person", ("person",)),
            ("pallet_jack", ("pallet_jack",)),
            ("with_people", ("person", "pallet_jack")),
        ):
            sel = [
                r
                for r in rows
                if r["map"] == map_kind and (kinds is None or r["scenario"] in kinds)
            ]
            if not sel:
                continue
            ratios = [
                r["travelled_over_optimal"] for r in sel if r["travelled_over_optimal"] is not None
            ]
            persons = [r["min_person_m"] for r in sel if r["min_person_m"] is not None]
            travelled = sum(r["travelled_m"] for r in sel)
            plans = [p for r in sel for p in r["plan_ms"]]
            ctl = [c for r in sel for c in r["controller_ms"]]
            out[f"{map_kind}/{group}"] = {
                "episodes": len(sel),
                "success_rate": float(np.mean([r["success"] for r in sel])),
                "collisions": int(sum(r["collisions"] for r in sel)),
                "episodes_with_collision": int(sum(r["collisions"] > 0 for r in sel)),
                "time_s_mean": float(np.mean([r["time_s"] for r in sel])),
                "barn_score_mean": float(np.mean([r["barn_score"] for r in sel])),
                "travelled_over_optimal_median": _pct(ratios, 50),
                "travelled_over_optimal_max": max(ratios) if ratios else None,
                "travelled_over_optimal_mean": float(np.mean(ratios)) if ratios else None,
                "final_error_true_m_p95": _pct([r.get("final_error_true_m") for r in sel], 95),
                "final_error_estimate_m_p95": _pct(
                    [r.get("final_error_estimate_m") for r in sel], 95
                ),
                "min_clearance_m": min(
                    (r["min_clearance_m"] for r in sel if r["min_clearance_m"] is not None),
                    default=None,
                ),
                "person_crossings": len(persons),
                "person_clearance_ge_0_3_share": float(np.mean([p >= 0.3 for p in persons]))
                if persons
                else None,
                "min_person_m": min(persons) if persons else None,
                "plan_ms_p50": _pct(plans, 50),
                "plan_ms_p95": _pct(plans, 95),
                "controller_ms_p50": _pct(ctl, 50),
                "controller_ms_p99": _pct(ctl, 99),
                "recoveries_per_100m": 100.0
                * sum(len(r["recoveries"]) for r in sel)
                / max(travelled, 1.0),
                "w_sign_changes_last_m_mean": float(
                    np.mean([r["w_sign_changes_last_m"] for r in sel])
                ),
            }
    return out
