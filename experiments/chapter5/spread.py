"""Chapter 5 over the parameters' uncertainty (``amr-twin experiment chapter5 --samples N``).

The eight runs (or those chosen) are simulated again with each configuration drawn by
:meth:`amr_twin.calibration.uncertainty.ParameterSpace.draw`, and measured as the nominal runs are
(:func:`.runs.analyse`). :func:`summarise` gives, per run, wheel and metric (published
samples and true speed), the nominal value, the median and 90 % interval over the draws,
the thesis' value and band where §5.1.3 gives one, and in how many draws the metric lies in
its band; each draw's scorecard (``draw_checks``: counted as the nominal run's, published and
true speed, :func:`.criteria.count_checks`; a setting no draw reads, such as
``wheel.tyre_slip``, leaves the draws as they are, so two runs of one seed compare draw by draw);
the §5.1.4 answers (the PI raises the duty with 20 kg; the 20 kg runs oscillate more) as the
number of draws in which they hold; and the parameters whose rank
correlation with each banded metric is largest; and each draw's run whose physics timestep the
tyres' guard halved (``tyre_timestep_halved``, :mod:`amr_twin.model.tyre_stability`).
``chapter5_spread_report.markdown`` writes the report's section (:mod:`.spread_report`); the run
plots get the 90 % band of the true wheel speed."""

from __future__ import annotations

import numpy as np

from amr_twin.calibration.draw_statistics import (
    LEVEL,
    interval,
    noise_level,
    rank_correlations,
)
from amr_twin.experiments.chapter5 import payload
from amr_twin.experiments.chapter5.runs import RUNS, RunJob, analyse, simulate
from amr_twin.experiments.chapter5.criteria import (
    BANDS,
    compare_oscillation,
    count_checks,
    step_class,
)

TOP = 3  # parameters named per banded metric
METRICS = ("delay_s", "rise_s", "peak_s", "settling_s", "overshoot", "steady_error", "oscillation")


def run(
    cfg,
    draws,
    jobs: int = 1,
    firmware: str = "faithful",
    runs: list[int] | None = None,
    duration_s: float | None = None,
    progress: bool = True,
) -> dict:
    """Simulate the runs once per draw; return the per-draw measurements and the speed bands.

    Returns ``{"draws": Draws, "samples": {i: [analysed runs, no raw series]}, "duty": {i: [...]},
    "bands": {run: {"t_s": [...], wheel: {"low", "median", "high"}}}}``.
    """
    import time

    from amr_twin.experiments.runner.executor import run_all

    wall0 = time.perf_counter()
    specs = [s for s in RUNS if runs is None or s.number in runs]
    configs = [draws.config(cfg, i) for i in range(len(draws))]
    todo = [
        RunJob(spec, configs[i], firmware, duration_s or spec.duration_s, extra={"sample": i})
        for i in range(len(draws))
        for spec in specs
    ]
    done: dict[int, list[dict]] = {}
    traces: dict[int, dict[str, list]] = {}
    for job, raw in run_all(simulate, todo, jobs, f"chapter 5 runs x {len(draws)} draws", progress):
        done.setdefault(job.extra["sample"], []).append(analyse(job.spec, raw))
        t = traces.setdefault(job.spec.number, {"t_s": raw["t_s"], "true": []})
        if len(raw["t_s"]) == len(t["t_s"]):
            t["true"].append(np.abs(raw["true_rpm"]))
    duty, samples = {}, {}
    for i in sorted(done):
        ordered = sorted(done[i], key=lambda r: r["run"])
        duty[i] = payload.duty_comparison(ordered)
        samples[i] = [{k: v for k, v in r.items() if k != "raw"} for r in ordered]
    bands = {}
    for number, t in traces.items():
        stack = np.array(t["true"])  # (draws, n, 2)
        q = np.quantile(stack, [(1 - LEVEL) / 2, 0.5, (1 + LEVEL) / 2], axis=0)
        bands[number] = {
            "t_s": t["t_s"],
            **{
                w: {"low": q[0][:, i], "median": q[1][:, i], "high": q[2][:, i]}
                for i, w in enumerate(("left", "right"))
            },
        }
    return {
        "draws": draws,
        "samples": samples,
        "duty": duty,
        "bands": bands,
        "wall_s": time.perf_counter() - wall0,
    }


def _thesis(metric: str, wheel: str, reference: float):
    for b in BANDS:
        if (
            b.metric == metric
            and b.step_class in ("any", step_class(reference))
            and b.wheel in ("any", wheel)
        ):
            return b
    return None


def summarise(nominal: dict, spread: dict) -> dict:
    """The JSON ``spread`` section (see the module notes)."""
    draws, samples = spread["draws"], spread["samples"]
    order = sorted(samples)
    x = draws.values[order]
    limit = noise_level(len(order), len(draws.names))
    metrics = []
    for r in nominal["runs"]:
        for wheel, w in r["wheels"].items():
            for source in ("published", "true"):
                for key in METRICS:
                    values = []
                    for i in order:
                        other = next(o for o in samples[i] if o["run"] == r["run"])["wheels"].get(
                            wheel, {}
                        )
                        values.append((other.get(source) or {}).get(key))
                    band = (
                        _thesis(key, wheel, w["reference_rpm"]) if source == "published" else None
                    )
                    entry = {
                        "run": r["run"],
                        "wheel": wheel,
                        "source": source,
                        "metric": key,
                        "nominal": (w[source] or {}).get(key),
                        **interval(values),
                    }
                    if band is not None:
                        inside = [v is not None and band.low <= v <= band.high for v in values]
                        rho = rank_correlations(x, values)
                        ranked = [
                            j
                            for j in np.argsort(-np.nan_to_num(np.abs(rho)))
                            if np.isfinite(rho[j])
                        ]
                        entry.update(
                            thesis=band.thesis,
                            band=[band.low, band.high],
                            in_band=int(sum(inside)),
                            drivers=[
                                {
                                    "parameter": draws.names[j],
                                    "rho": round(float(rho[j]), 3),
                                    "notable": bool(abs(rho[j]) > limit),
                                }
                                for j in ranked[:TOP]
                            ],
                        )
                    metrics.append(entry)
    oscillation = [compare_oscillation(samples[i]) for i in order]
    keys = ("draw", "checks", "passed", "true_checks", "true_passed")
    draw_checks = [
        dict(zip(keys, (i, *count_checks(samples[i], comps))))
        for i, comps in zip(order, oscillation)
    ]
    pairs = {}
    for comps in oscillation:
        for c in comps:
            p = pairs.setdefault(
                (c["loaded_run"], c["unloaded_run"], c["wheel"]), {"published": 0, "true": 0}
            )
            p["published"] += c["verdict"] == "pass"
            p["true"] += c["true_verdict"] == "pass"
    raised = {}
    for i in order:
        for d in spread["duty"][i]:
            raised[(d["loaded_run"], d["unloaded_run"], d["wheel"])] = raised.get(
                (d["loaded_run"], d["unloaded_run"], d["wheel"]), 0
            ) + bool(d["raised"])
    return {
        "samples": len(order),
        "wall_s": round(spread["wall_s"], 3),
        "seed": draws.seed,
        "sampler": draws.sampler,
        "level": LEVEL,
        "parameters": list(draws.names),
        "clipped": draws.clipped,
        "noise_level_rho": limit,
        "metrics": metrics,
        "draw_checks": draw_checks,
        "checks_passed": {
            source: interval([d[key] for d in draw_checks], discrete=True)
            for source, key in (("published", "passed"), ("true", "true_passed"))
        },
        "oscillation_more": [
            {
                "loaded_run": a,
                "unloaded_run": b,
                "wheel": w,
                "draws_published": v["published"],
                "draws_true": v["true"],
            }
            for (a, b, w), v in pairs.items()
        ],
        "oscillation_all_hold": sum(
            all(c["verdict"] == "pass" for c in comps) and bool(comps) for comps in oscillation
        ),
        "duty_raised": [
            {"loaded_run": a, "unloaded_run": b, "wheel": w, "draws": v}
            for (a, b, w), v in raised.items()
        ],
        "tyre_timestep_halved": [
            {"draw": i, "run": r["run"], **r["tyre_timestep"]}
            for i in order
            for r in samples[i]
            if r.get("tyre_timestep")
        ],
    }
