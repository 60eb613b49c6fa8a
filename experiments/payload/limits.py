"""What limits a payload: the causes a sweep point fails by (:func:`limit_causes`, in words
:func:`unsafe_reason`), the driven wheel that left its reference (:func:`off_reference`) and the
line a plotted column is judged against (:func:`column_limit`)."""

from __future__ import annotations

from amr_twin.experiments.chapter5.criteria import WHEELS
from amr_twin.experiments.payload.simulation import (
    RUNAWAY_RPM,
    TILT_LIMIT_DEG,
    TIP_MARGIN_MIN_M,
    TRACK_TOLERANCE_RPM,
)

CAUSES = {
    "invalid": "invalid payload",
    "refused": "command refused",
    "failed": "simulation failed",
    "runaway": "runaway (the wheels leave their references; the motor current follows)",
    "overload": "motor current rating (wheels tracking)",
    "tipping": "tipping (static tip margin)",
    "lift-off": "drive-wheel lift-off",
    "tilt": "base tilt",
}
"""What limits a payload, by the criteria a point fails (``limit_causes``). A motor over its
rating while a wheel does not hold its reference (its true speed over the run's last quarter
more than the PI's 4 RPM dead zone off) is a **runaway**: a limit of the speed control (a robot
heavy at the rear oversteers in the turn and, its wheels not held, pivots), not the current the
payload demands in a tracked turn."""


def limit_causes(row: dict) -> list[tuple[str, str]]:
    """``[(cause, detail)]``: why a row is not safe (empty when it is); causes of :data:`CAUSES`."""
    if row.get("safe"):
        return []
    if not row.get("valid", True):
        return [("invalid", row["error"])]
    if row.get("error"):
        return [
            ("refused" if row["error"].startswith("command refused") else "failed", row["error"])
        ]
    out = []
    if row.get("motor_overload"):
        worst = max(row.get(f"{w}_steady_current_a") or 0.0 for w in WHEELS)
        rating = row.get("current_limit_a")
        current = f"{worst:.1f} A steady" + (f" > {rating:.1f} A" if rating is not None else "")
        off = off_reference(row)
        if off is None:
            out.append(("overload", current))
        else:
            out.append(("runaway", f"{off}, {current}"))
    if row.get("static_tip_margin_m", -1) < TIP_MARGIN_MIN_M:
        out.append(("tipping", f"{row.get('static_tip_margin_m')} m < {TIP_MARGIN_MIN_M} m"))
    if row.get("wheel_lift_off", True):
        out.append(("lift-off", f"min load {row.get('dyn_min_wheel_n', float('nan')):.1f} N"))
    if row.get("max_tilt_deg", 90) > TILT_LIMIT_DEG:
        out.append(
            ("tilt", f"{row.get('max_tilt_deg', float('nan')):.2f} deg > {TILT_LIMIT_DEG} deg")
        )
    return out


def off_reference(row: dict) -> str | None:
    """The driven wheel whose true speed (the run's last quarter) left its reference by more than
    :data:`~amr_twin.experiments.payload.simulation.RUNAWAY_RPM`, in words; None if none did."""
    off = max(
        (
            (abs(e), w)
            for w in WHEELS
            if row.get(f"{w}_reference_rpm")
            and (e := row.get(f"{w}_true_steady_error_rpm")) is not None
        ),
        default=(0.0, ""),
    )
    if off[0] <= RUNAWAY_RPM:
        return None
    ref = abs(row[f"{off[1]}_reference_rpm"])
    speed = (
        ref + row[f"{off[1]}_true_steady_error_rpm"]
    )  # along the reference: < 0 turning backward
    return f"{off[1]} wheel at {speed:.0f} RPM against {ref:.1f}"


def unsafe_reason(row: dict) -> str:
    """Why a row is not safe ('' when it is), in words."""
    return "; ".join(f"{CAUSES[c]}: {d}" for c, d in limit_causes(row))


def column_limit(column: str, rows: list[dict]) -> tuple[float, str] | None:
    """The line a panel's values are judged against (a point's safety or tracking), if any."""
    from amr_twin.model.statics import CONTACT_MIN_N

    rating = next(
        (r["current_limit_a"] for r in rows if r.get("current_limit_a") is not None), None
    )
    limits = {
        "~steady_current_a": (rating, "driver's continuous rating"),
        "max_tilt_deg": (TILT_LIMIT_DEG, "tilt"),
        "static_tip_margin_m": (TIP_MARGIN_MIN_M, "tip margin"),
        "dyn_min_wheel_n": (CONTACT_MIN_N, "lift-off"),
        "~steady_error_rpm": (TRACK_TOLERANCE_RPM, "tracking (the PI's dead zone)"),
    }
    value, name = limits.get(column, (None, ""))
    return None if value is None else (float(value), name)
