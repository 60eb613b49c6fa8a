"""The outputs of the navigation experiment on generated halls: ``metrics.json``, ``report.md`` and,
for each hall, a folder with the world (MJCF, map_server YAML + PGM) and the trajectories over its
map."""

from __future__ import annotations

from pathlib import Path

from amr_twin.experiments.runner.executor import write_json, write_text
from amr_twin.experiments.navigation.report import _fmt, plot
from amr_twin.experiments.navigation.result import HallsResult


def world_folder(world: str) -> str:
    """The folder name of a hall's outputs: ``generated_SEED`` or ``generated_SEED_doorW``."""
    from amr_twin.model.generated_world import parse

    seed, door = parse(world)
    return f"generated_{seed}" + ("" if door is None else f"_door{door:g}")


def write_worlds(cfg, result: HallsResult, out: Path) -> None:
    """Each hall's world files (:func:`~.generated.write_world`) and ``trajectories_true.png``."""
    from amr_twin.experiments.navigation.generated import write_world

    for world in result.worlds:
        folder = out / world_folder(world)
        write_world(cfg, world, folder)
        plot(
            [r for r in result.rows if r["world"] == world],
            {"true": result.static_maps[world]},
            folder,
        )


def _share(ok: int, n: int) -> str:
    return f"{ok} of {n} ({100 * ok / n:.0f} %)" if n else "-"


def _door_cells(d: dict) -> str:
    return (
        f"{_share(d['success'], d['episodes'])} | {d['collisions']} | {d['door_passages']} | "
        f"{_fmt(d['door_clearance_min_m'], 3)} / {_fmt(d['door_clearance_median_m'], 3)} | "
        f"{_fmt(d['final_error_true_m_median'], 3)} / {_fmt(d['final_error_true_m_max'], 3)}"
    )


def _people_lines(data: dict) -> list[str]:
    """The people table: person episodes, their successes and contacts, the time they cost against
    the same episodes without them (:func:`~.generated.people_penalty`)."""
    lines = [
        "",
        f"People (`{data['people']}`): each episode with a walking person also run without them "
        f"(same hall, "
        "start, goal and seeds); extra time to the goal over the pairs both reached. A contact: "
        "any touch of "
        "person and robot (a reported collision naming the person).",
        "",
        "| halls | person episodes | reached | episodes touching a person | pairs | extra s "
        "median | extra s worst |",
        "|" + "---|" * 7,
    ]
    for group, s in data["summary"].items():
        p = s.get("people")
        if p is None:
            continue
        lines.append(
            f"| {group.replace('_', '-')} | {p['person_episodes']} | "
            f"{_share(p['person_success'], p['person_episodes'])} | "
            f"{p['person_contact_episodes']} | {p['pairs']} | "
            f"{_fmt(p['extra_s_median'], 1)} | {_fmt(p['extra_s_max'], 1)} |"
        )
    return lines


def report(data: dict, out: Path) -> None:
    """Write ``metrics.json`` and ``report.md``: the tuning halls and the held-out ones apart."""
    write_json(out / "metrics.json", data)
    head = (
        "| halls | trips | episodes | success | collisions | doorway passages | least jamb "
        "clearance m "
        "(min / median) | true final error m (median / max) |"
    )
    lines = [
        f"# Navigation on generated halls: {data['episodes']} episodes x {len(data['worlds'])} "
        f"halls",
        "",
        f"Tuning halls (tuned on, not to be quoted as results): "
        f"{', '.join(data['groups']['tuning']) or 'none'}. "
        f"Held-out halls: {', '.join(data['groups']['held_out']) or 'none'}.",
        "",
        f"Episode seed {data['seed']}, people `{data['people']}`, localisation "
        f"`{data['localisation']}`, "
        f"controller `{data['controller']}`, firmware `{data['firmware']}`, the true map. "
        f"Success: the "
        "metrics' rule (the true pose at the end within the goal checker's tolerances, no "
        "collision). "
        "Jamb clearance: the true footprint to each side of the doorway while in it. "
        f"Optimal length: {data['optimal']}.",
        "",
        head,
        "|" + "---|" * 8,
    ]
    for group, s in data["summary"].items():
        for trips, d in s["doors"].items():
            lines.append(
                f"| {group.replace('_', '-')} | {trips.replace('_', ' ')} | {d['episodes']} | "
                f"{_door_cells(d)} |"
            )
    lines += ["", "Per hall:", "", head.replace("| halls |", "| hall |"), "|" + "---|" * 8]
    for world, s in data["by_world"].items():
        for trips, d in s.items():
            lines.append(
                f"| `{world}` | {trips.replace('_', ' ')} | {d['episodes']} | {_door_cells(d)} |"
            )
    lines += [
        "",
        "| halls | episodes | success | travelled/optimal median (max) | min clearance m | "
        "person >= 0.3 m |",
        "|" + "---|" * 6,
    ]
    for group, s in data["summary"].items():
        v = s["episodes"].get("true/all")
        lines.append(
            f"| {group.replace('_', '-')} | {v['episodes']} | "
            f"{_fmt(v['success_rate'], 1, 100, ' %')} | "
            f"{_fmt(v['travelled_over_optimal_median'], 3)} "
            f"({_fmt(v['travelled_over_optimal_max'], 3)}) | "
            f"{_fmt(v['min_clearance_m'], 3)} | "
            f"{_fmt(v['person_clearance_ge_0_3_share'], 0, 100, ' %')} of {v['person_crossings']} |"
        )
    lines += _people_lines(data)
    failed = [r for r in data["rows"] if not r["success"]]
    lines += ["", f"Failed episodes ({len(failed)}):", ""]
    for r in failed:
        gaps = "; ".join(
            f"{k} {c['width_m']:g} m: jambs {c['south_m']:.3f} / {c['north_m']:.3f} m"
            for k, c in r.get("door_clearance", {}).items()
        )
        lines.append(
            f"- `{r['world']}` episode {r['index']} ({r['scenario']}, "
            f"{'door trip' if r['door_trip'] else 'one side'}): {r['status']}"
            f"{', ' + str(r['collisions']) + ' collision(s) with ' if r['collisions'] else ''}"
            f"{', '.join(r['collided_with']) if r['collisions'] else ''}"
            f"{': ' + r['reason'] if r['reason'] else ''}; true final error "
            f"{_fmt(r.get('final_error_true_m'), 2)} m{'; ' + gaps if gaps else ''}"
        )
    if not failed:
        lines.append("- none")
    lines += [
        "",
        f"Wall time {data['wall_s']:.0f} s, CPU {data['cpu_s']:.0f} s (all processes), "
        f"{data['jobs']} job(s).",
        "",
        "Each hall's folder holds its world (`.xml`), its true map (`.yaml` + `.pgm`) and the "
        "trajectories:",
        "",
    ]
    lines += [f"- [`{w}`]({world_folder(w)}/trajectories_true.png)" for w in data["worlds"]]
    write_text(out / "report.md", "\n".join(lines) + "\n")
