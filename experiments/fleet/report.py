"""The fleet experiment's report: by payload mix and fleet size the medians over seeds, where
throughput saturates, energy per order by payload bin; ``metrics.json``, ``report.md``,
``throughput.png`` (orders per hour against fleet size, a point per seed, the median line) and
``tracks_<N>.png`` (every robot's true track on the map, the first seed of the first mix)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from statistics import median

from amr_twin.experiments.fleet import metrics
from amr_twin.experiments.fleet.result import EpisodeResult
from amr_twin.experiments.runner.executor import save_figure, write_json, write_text


def _median(values: list) -> float | None:
    values = [v for v in values if v is not None]
    return round(median(values), 4) if values else None


@dataclass(frozen=True)
class FleetResult:
    """The episodes, in the spec's order (payload mix, fleet size, seed)."""

    episodes: list[EpisodeResult]

    def summary(self) -> list[dict]:
        """Per payload mix: per fleet size the medians over seeds and the sums of the incidents,
        the saturating fleet size (:func:`~.metrics.saturation`), energy per order by payload
        bin over every episode of the mix."""
        out = []
        for mix in dict.fromkeys(e.point.payload_kg for e in self.episodes):
            eps = [e for e in self.episodes if e.point.payload_kg == mix]
            sizes = sorted({e.point.robots for e in eps})
            rows = []
            for n in sizes:
                group = [e for e in eps if e.point.robots == n]
                util = [r.utilisation for e in group for r in e.robots]
                rows.append(
                    {
                        "robots": n,
                        "seeds": [e.point.seed for e in group],
                        "orders_per_hour": [e.orders_per_hour for e in group],
                        "orders_per_hour_median": _median([e.orders_per_hour for e in group]),
                        "lead_time_p50_s_median": _median([e.lead_time_p50_s for e in group]),
                        "lead_time_p95_s_median": _median([e.lead_time_p95_s for e in group]),
                        "utilisation_median": _median(util),
                        "energy_per_order_wh_median": _median(
                            [e.energy_per_order_wh for e in group]
                        ),
                        "charging_s_median": _median(
                            [sum(r.charging_s for r in e.robots) for e in group]
                        ),
                        "deadlocks": sum(e.deadlocks for e in group),
                        "collisions": sum(e.collisions for e in group),
                        "near_misses": sum(len(e.near_misses) for e in group),
                        "least_distance_m": min(
                            (e.least_distance_m for e in group if e.least_distance_m is not None),
                            default=None,
                        ),
                    }
                )
            done = [
                {
                    "payload_kg": j.payload_kg,
                    "energy_wh": j.energy_wh,
                    "driving_wh": j.driving_wh,
                    "distance_m": j.distance_m,
                }
                for e in eps
                for j in e.jobs
                if j.energy_wh is not None
            ]
            out.append(
                {
                    "payload_kg": list(mix),
                    "by_fleet_size": rows,
                    "saturates_at_robots": metrics.saturation(
                        sizes, [r["orders_per_hour_median"] for r in rows]
                    ),
                    "energy_by_payload": metrics.payload_bins(done, metrics.bin_edges(*mix)),
                    "driving_energy_fit": metrics.payload_slope(done),
                }
            )
        return out

    def as_json(self) -> dict:
        return {
            "summary": self.summary(),
            "episodes": [e.as_json() for e in self.episodes],
        }


def write(result: FleetResult, cfg, out: Path) -> None:
    """``metrics.json``, ``report.md`` and the plots in ``out``."""
    data = result.as_json()
    write_json(out / "metrics.json", data)
    write_text(out / "report.md", markdown(data))
    plot_throughput(data["summary"], out / "throughput.png")
    first = data["summary"][0]["payload_kg"] if data["summary"] else None
    shown = {}
    for e in data["episodes"]:
        if list(e["point"]["payload_kg"]) == first:
            shown.setdefault(e["point"]["robots"], e)
    for n, e in shown.items():
        plot_tracks(cfg, e, out / f"tracks_{n}.png")


def _f(v, fmt: str = ".1f") -> str:
    return "-" if v is None else format(v, fmt)


def markdown(data: dict) -> str:
    """The report: one table a payload mix, the saturation sentence, energy by payload bin."""
    lines = ["# How many AMRs: the fleet experiment", ""]
    eps = data["episodes"]
    if eps:
        p = eps[0]["point"]
        lines += [
            f"World `{p['world']}`, {p['duration_s']:g} s simulated an episode, orders arriving at "
            f"{p['jobs_per_hour']:g} an hour (Poisson), near miss: true centres closer than "
            f"{p['near_miss_m']:g} m. Lead time: arrival to drop finished.",
            "",
        ]
    for mix in data["summary"]:
        lo, hi = mix["payload_kg"]
        lines += [
            f"## Payload {lo:g}-{hi:g} kg",
            "",
            "| robots | orders/h (median; per seed) | lead p50 s | lead p95 s | utilisation | "
            "Wh/order | charging s | deadlocks | collisions | near misses | least distance m |",
            "|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        for r in mix["by_fleet_size"]:
            seeds = ", ".join(_f(v) for v in r["orders_per_hour"])
            lines.append(
                f"| {r['robots']} | {_f(r['orders_per_hour_median'])} ({seeds}) | "
                f"{_f(r['lead_time_p50_s_median'])} | {_f(r['lead_time_p95_s_median'])} | "
                f"{_f(r['utilisation_median'], '.2f')} | "
                f"{_f(r['energy_per_order_wh_median'], '.3f')} | {_f(r['charging_s_median'])} | "
                f"{r['deadlocks']} | {r['collisions']} | {r['near_misses']} | "
                f"{_f(r['least_distance_m'], '.2f')} |"
            )
        sizes = [r["robots"] for r in mix["by_fleet_size"]]
        sat = mix["saturates_at_robots"]
        gain = round(100 * metrics.SATURATION_GAIN)
        if len(sizes) < 2:
            lines += ["", f"Saturation: one fleet size ({sizes[0]}) only: not determined."]
        elif sat is None:
            lines += [
                "",
                f"Saturation: none up to {max(sizes)} robots (every step adds >= {gain} %).",
            ]
        else:
            lines += [
                "",
                f"Saturation: throughput saturates at {sat} robots: the next fleet size adds "
                f"less than {gain} % orders per hour.",
            ]
        lines += [
            "",
            "Energy per order by payload (Wh/order: from assignment to drop finished, standing "
            "included; driving Wh/km: drawn while moving, over the distance driven):",
            "",
            "| payload kg | orders | Wh/order (median) | driving Wh/km (median) |",
            "|---|---|---|---|",
        ]
        for b in mix["energy_by_payload"]:
            a, z = b["payload_kg"]
            lines.append(
                f"| {a:g}-{z:g} | {b['orders']} | {_f(b['energy_wh_median'], '.3f')} | "
                f"{_f(b['driving_wh_per_km_median'], '.2f')} |"
            )
        fit = mix["driving_energy_fit"]
        if fit is not None:
            lines += [
                "",
                f"Least-squares line through the {fit['orders']} orders: driving energy "
                f"{fit['wh_per_km_at_0kg']:.2f} Wh/km unloaded, {fit['wh_per_km_per_10kg']:+.2f} "
                "Wh/km per 10 kg of payload.",
            ]
        lines.append("")
    return "\n".join(lines) + "\n"


def plot_throughput(summary: list[dict], path: Path) -> None:
    """Orders per hour against fleet size: a point per seed, the median line, one colour a mix."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for mix in summary:
        label = "{:g}-{:g} kg".format(*mix["payload_kg"])
        rows = mix["by_fleet_size"]
        pts = [(r["robots"], q) for r in rows for q in r["orders_per_hour"]]
        line = ax.plot(
            [r["robots"] for r in rows],
            [r["orders_per_hour_median"] for r in rows],
            "-",
            label=f"{label} (median)",
        )
        ax.plot([p[0] for p in pts], [p[1] for p in pts], "o", color=line[0].get_color(), ms=4)
        if mix["saturates_at_robots"] is not None:
            ax.axvline(mix["saturates_at_robots"], color=line[0].get_color(), ls=":")
    ax.set_xlabel("robots")
    ax.set_ylabel("orders per hour")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path)


def plot_tracks(cfg, episode: dict, path: Path) -> None:
    """Every robot's true track of ``episode`` over the world's occupancy map."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from amr_twin.navigation.stack import load_static_map

    sm = load_static_map(cfg, episode["point"]["world"], None)
    h, w = sm.shape
    x0, y0 = sm.origin_xy_m
    extent = (x0, x0 + w * sm.resolution_m, y0, y0 + h * sm.resolution_m)
    fig, ax = plt.subplots(figsize=(10, 6))
    ax.imshow(
        np.where(sm.occupied, 0.0, 1.0),
        origin="lower",
        extent=extent,
        cmap="gray",
        vmin=0,
        vmax=1,
        interpolation="nearest",
    )
    for r in episode["robots"]:
        xy = np.asarray([p[1:] for p in r["track"]], float).reshape(-1, 2)
        ax.plot(xy[:, 0], xy[:, 1], "-", lw=1.0, label=r["serial"])
    ax.set_title(f"{len(episode['robots'])} robot(s), seed {episode['point']['seed']}")
    ax.set_aspect("equal")
    ax.legend(loc="upper right", fontsize=7)
    fig.tight_layout()
    save_figure(fig, path)
