"""``summary.md`` of a payload sweep with ``--samples N`` (:func:`markdown`): the highest safe
payload per position and each position's and command's lift-off, tilt, tip margin and overload,
nominal and over the draws (median and 90 % interval), with the parameters that move each."""

from __future__ import annotations

import math

from amr_twin.calibration.draw_statistics import LEVEL, noise_level
from amr_twin.experiments.payload import spread
from amr_twin.experiments.payload.rows import lowest_wheel_loads
from amr_twin.experiments.payload.simulation import TILT_LIMIT_DEG, TIP_MARGIN_MIN_M


def _kg(v) -> str:
    if v is None:
        return "—"
    if v == math.inf:
        return "none in sweep"
    return "none safe" if v == -math.inf else f"{v:g}"


def _span(a: dict, top: float) -> str:
    """``median (low – high)`` of an answer; ``> top`` for draws beyond the sweep."""

    def one(v):
        return (
            f"> {top:g}"
            if v == math.inf
            else _kg(v)
            if v == -math.inf
            else ("—" if v is None else f"{v:.3g}")
        )

    if a["n"] == 0:
        return "—"
    return f"{one(a['median'])} ({one(a['low'])} – {one(a['high'])})"


def _who(sens, position, command, answer) -> str:
    rows = spread.drivers(sens, position, command, answer)
    return (
        ", ".join(
            ("**`{}` {:+.2f}**" if r["notable"] else "`{}` {:+.2f}").format(
                r["parameter"], r["rho"]
            )
            for r in rows
        )
        or "—"
    )


def markdown(results, base, found, sens, top, n) -> str:
    """The text of ``summary.md``: ``base`` the nominal :func:`.sweep_report.summarise`, ``found``
    and ``sens`` :func:`.spread.answers` and :func:`.spread.sensitivity`, ``top`` the heaviest mass
    swept, kg, ``n`` the draws."""
    draws = results["draws"]
    lines = [
        "# Payload sweep with parameter uncertainty",
        "",
        f"{len(base)} positions; {len(results['rows'])} runs "
        f"({results['simulated']} simulated, {results['reused']} reused) in "
        f"{results['wall_s']:.1f} s wall time; "
        f"{results['duration_s']} s per run, firmware {results['firmware']}. Each point was run "
        f"with the "
        f"nominal parameters and with {n} configurations drawn from the parameters' spreads "
        f"({draws.sampler}, seed {draws.seed}, {len(draws.names)} parameters varied: "
        f"`samples.csv`; spreads in "
        "`models/amr/README.md`).",
        "",
        f"Safe: valid position, simulation ran, static tip margin >= {TIP_MARGIN_MIN_M} m, no "
        f"drive-wheel "
        f"lift-off, base tilt <= {TILT_LIMIT_DEG} deg, no motor above the driver's continuous "
        f"current (the draw's "
        "rating), for every command and every lighter payload. Intervals: "
        f"median ({LEVEL:.0%} interval) over the draws. What moves it: the {spread.TOP} "
        f"parameters of largest "
        f"Spearman rank correlation with the answer over the draws; **bold** beyond chance "
        f"(|rho| > "
        f"{noise_level(n, len(draws.names)):.2f}: the largest of {len(draws.names)} unrelated "
        f"parameters reaches "
        f"it about one time in 20 with {n} draws; the others are candidates, not findings).",
        "",
        "## Highest safe payload per position",
        "",
        f"| position | nominal kg | over the draws kg | draws unsafe within {top:g} kg | unsafe "
        f"first (nominal) | "
        "what moves it |",
        "|---|---|---|---|---|---|",
    ]
    for position, b in base.items():
        a = found[position]["highest_safe_kg"]
        first = (
            f"{b['first_unsafe_kg']:g} kg: {b['reason']}"
            if b["first_unsafe_kg"] is not None
            else "—"
        )
        lines.append(
            f"| {position} | {_kg(a['nominal'])} | {_span(a, top)} | {a['within']} of {a['n']} | "
            f"{first} | "
            f"{_who(sens, position, '', 'highest_safe_kg')} |"
        )
    lines += [
        "",
        "## Lift-off, tilt, tip margin and motor overload per position and command",
        "",
        "Payload (kg) from which it happens, interpolated between the swept masses; "
        f"`> {top:g}`: not within the sweep.",
        "",
        f"| position | command | answer | nominal kg | over the draws kg | draws within {top:g} "
        f"kg | what moves it |",
        "|---|---|---|---|---|---|---|",
    ]
    for position, entry in found.items():
        for command, per in entry["commands"].items():
            for answer, a in per.items():
                nominal = _span(
                    {"n": 1, "median": a["nominal"], "low": None, "high": None}, top
                ).split(" (")[0]
                lines.append(
                    f"| {position} | {command} | {spread.ANSWER_TEXT[answer]} | {nominal} | "
                    f"{_span(a, top)} | {a['within']} of {a['n']} | "
                    f"{_who(sens, position, command, answer)} |"
                )
    if draws.clipped:
        lines += [
            "",
            "Draws clipped to a bound (schema or calibration): "
            + ", ".join(f"`{k}` {v} of {len(draws)}" for k, v in draws.clipped.items())
            + ".",
        ]
    lines += [
        "",
        *lowest_wheel_loads(spread.split(results)[0]),
        "",
        "`intervals.csv`: every metric per point (nominal, median, interval); `sensitivity.csv`: "
        "every "
        "parameter's rank correlation with every answer.",
        "",
    ]
    commands = dict.fromkeys(r["command"] for r in spread.split(results)[0])
    lines += [
        f"![{name}]({name})" for name in (f"sweep_{c.replace(':', '_')}.png" for c in commands)
    ]
    lines += ["![sensitivity](sensitivity.png)"]
    return "\n".join(lines) + "\n"
