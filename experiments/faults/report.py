"""The fault study's outputs: ``faults.md`` (the document), ``faults.json`` and
``img/faults_<case>.png``.

The committed page (:data:`PAGE`) and measures (:data:`COMMITTED_JSON`) are rewritten by
``python -m amr_twin.experiments.documents.figures``. The outputs hold no wall time: the same
code gives the same files, and a change of the plant shows as a diff.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from amr_twin.sim.faults import KINDS, kind_names, parse_fault
from amr_twin.recording.run_summary import json_ready
from amr_twin.experiments.runner.executor import save_figure, write_text
from amr_twin.experiments.faults.experiment import (
    FAULT_T_S,
    FIRMWARES,
    REFERENCE_RPM,
    SCENARIO,
    STOP_T_S,
)
from amr_twin.experiments.faults.readings import number, reading
from amr_twin.model.paths import ROOT

COMMITTED_JSON = ROOT / "experiments" / "faults" / "reference" / "faults.json"
"""The committed measures the documents quote."""
PAGE = ROOT / "docs" / "reference" / "faults.md"
"""The committed page, written from :data:`COMMITTED_JSON`; its figures are in ``docs/img/``."""


def _slug(case: str) -> str:
    return (
        case.replace("@", "_at_")
        .replace(":", "_")
        .replace(",", "_")
        .replace("=", "")
        .replace(".", "p")
    )


def plot(results: dict, out: Path) -> list[Path]:
    """One figure per case: wheel speeds (true, published) and the path, per firmware, against the
    baseline."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    raw, paths = results["raw"], []
    for case in results["cases"]:
        fault = parse_fault(case)
        fig, axes = plt.subplots(2, 2, figsize=(10, 6.2), gridspec_kw={"width_ratios": [2.2, 1]})
        for row, fw in enumerate(FIRMWARES):
            r, base = raw[(case, fw)], raw[(None, fw)]
            ax = axes[row, 0]
            end = fault.until_s if fault.until_s is not None else r["t_s"][-1]
            ax.axvspan(fault.t_s, end, color="0.85", label="fault")
            ax.axvline(STOP_T_S, color="k", lw=0.8, ls=":", label="stop sent")
            for w, (name, color) in enumerate((("left", "tab:blue"), ("right", "tab:orange"))):
                ax.plot(r["t_s"], r["true_rpm"][:, w], color=color, lw=1.2, label=f"{name} true")
                pub = r["published"][w]
                if len(pub):
                    ax.plot(
                        pub[:, 0],
                        pub[:, 1],
                        "o",
                        ms=2.5,
                        color=color,
                        alpha=0.7,
                        label=f"{name} published",
                    )
            ax.axhline(REFERENCE_RPM, color="0.4", lw=0.6, ls="--")
            ax.set_ylim(-5, max(70.0, min(200.0, float(np.nanmax(r["true_rpm"])) + 5)))
            ax.set_ylabel(f"{fw}\nwheel speed, RPM")
            ax.grid(alpha=0.3)
            ax2 = axes[row, 1]
            ax2.plot(base["pose"][:, 0], base["pose"][:, 1], "--", color="0.5", label="no fault")
            ax2.plot(r["pose"][:, 0], r["pose"][:, 1], color="tab:red", label="with the fault")
            k = np.searchsorted(r["t_s"], fault.t_s)
            ax2.plot(*r["pose"][min(k, len(r["pose"]) - 1), :2], "kx", label="fault")
            ax2.set_aspect("equal", adjustable="datalim")
            ax2.grid(alpha=0.3)
            ax2.set_ylabel("y, m")
        axes[0, 0].legend(loc="upper right", fontsize=7, ncol=3)
        axes[0, 1].legend(loc="best", fontsize=7)
        axes[1, 0].set_xlabel("time, s")
        axes[1, 1].set_xlabel("x, m")
        fig.suptitle(f"--fault {case}", fontsize=11)
        fig.tight_layout()
        path = Path(out) / "img" / f"faults_{_slug(case)}.png"
        save_figure(fig, path, dpi=72)
        paths.append(path)
    return paths


def markdown(results: dict, images: str = "img") -> str:
    """``faults.md``: how to inject faults, the table of kinds, the study's table, plots and
    readings; ``images`` is the figures' folder relative to the page."""
    rows = {(r["fault"], r["firmware"]): r for r in results["rows"]}
    lines = [
        "# Fault injection",
        "",
        "The twin's faults are the robot's own: a sensor that stops or lies, a wheel that jams "
        "or leaves the "
        "ground, a serial link that drops or delays frames, a battery that sags or is cut, the "
        "e-stop. Inject "
        "them with `--fault KIND@T[:ARGS]` (repeatable) on `amr-twin run` and `amr-twin client`, "
        "or list them "
        "under `faults:` in a mission file. `T` is in seconds from the start; `ARGS` is the "
        "kind's parameter "
        "(bare or by name) and `for=S` to clear the fault after `S` seconds:",
        "",
        "```",
        "amr-twin run linear --speed-m-s 0.5 --duration-s 10 --world empty --fault "
        "hall-left-dead@3 --json",
        "amr-twin run --mission m.yaml --fault rosserial-loss@2:0.3,for=5 --fault estop@6:for=1",
        "```",
        "",
        "| kind | parameter (default) | what happens |",
        "|---|---|---|",
    ]
    for kind, spec in KINDS.items():
        names = [n for n in kind_names() if parse_fault(f"{n}@0").kind == kind]
        param = f"`{spec.param}` ({spec.default})" if spec.param else "-"
        lines.append(f"| {' / '.join(f'`{n}`' for n in names)} | {param} | {spec.summary} |")
    lines += [
        "",
        "The JSON summary of a run (`--json`) lists each fault under `faults` with its `effect`: "
        "per wheel "
        "the mean true speed before the fault and at the end, the peak after it, the speeds "
        "published after "
        "it and the last one, the PWM at the end; the distance driven after it; for sensor "
        "faults the "
        "messages published after it. Recordings carry them as `/twin/faults` (diagnostic_msgs/"
        "DiagnosticArray) in the `.mcap` and `events/faults` in the `.rrd`. The faults act "
        "through small "
        "hooks of the components (`amr_twin/sim/fault_injector.py`); random draws (frame loss, "
        "chatter) follow "
        "`--seed`.",
        "",
        "## What the firmwares do",
        "",
        f"Scenario: {SCENARIO}. `python -m amr_twin.experiments.documents.figures` regenerates "
        "the committed page and its figures (after any change of the plant or the firmwares). "
        f"Wheel speeds are true speeds in RPM (reference {REFERENCE_RPM:.1f}); *during* is the "
        f"mean over the "
        f"last 0.5 s of the fault (before the stop at {STOP_T_S:g} s); *offset* is the distance "
        f"and heading "
        "between the robot's final pose and its fault-free run's; *after stop* is the distance "
        "driven from "
        f"{STOP_T_S + 0.5:g} s on.",
        "",
        "| fault | firmware | left before / during | right during | left published during | "
        "offset m / deg "
        "| after stop m | stopped |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for case in results["cases"]:
        for fw in FIRMWARES:
            r = rows[(case, fw)]
            L, R = r["wheels"]["left"], r["wheels"]["right"]
            lines.append(
                f"| `{case}` | {fw} | {number(L['true_before_rpm'])} / "
                f"{number(L['true_during_rpm'])} | "
                f"{number(R['true_during_rpm'])} | {L['published_during']} | "
                f"{number(r['end_offset_m'], '.2f')} / "
                f"{number(r['end_heading_offset_deg'], '.0f')} | "
                f"{number(r['moved_after_stop_m'], '.2f')} | "
                f"{'yes' if r['stopped_at_end'] else '**no**'} |"
            )
    lines += [""]
    for case in results["cases"]:
        fault = parse_fault(case)
        lines += [
            f"### `{case}`",
            "",
            f"*What happens:* {KINDS[fault.kind].summary}.",
            "",
            reading(case, {fw: rows[(case, fw)] for fw in FIRMWARES}),
            "",
            f"![{case}]({images}/faults_{_slug(case)}.png)",
            "",
        ]
    return "\n".join(lines)


def measures(results: dict) -> dict:
    """What ``faults.json`` holds: the scenario, the fault and stop times (s) and the rows."""
    return {
        "scenario": SCENARIO,
        "fault_t_s": FAULT_T_S,
        "stop_t_s": STOP_T_S,
        "rows": results["rows"],
    }


def _json_text(data: dict) -> str:
    return json.dumps(json_ready(data), indent=2, allow_nan=False) + "\n"


def report(results: dict, out: Path) -> dict:
    """Write ``faults.md`` and ``faults.json`` (the measures) in ``out``; return the measures."""
    data = measures(results)
    write_text(Path(out) / "faults.json", _json_text(data))
    write_text(Path(out) / "faults.md", markdown(results))
    return data


def committed_write(results: dict) -> dict:
    """Write :data:`COMMITTED_JSON`, :data:`PAGE` and the figures in ``docs/img/``; return the
    measures."""
    plot(results, ROOT / "docs")
    data = measures(results)
    write_text(COMMITTED_JSON, _json_text(data))
    write_text(PAGE, markdown(results, images="../img"))
    return data
