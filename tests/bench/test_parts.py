"""The parts profiler: exclusive times of nested parts, a run's parts adding up to its total
(not timed)."""

import subprocess
import sys

from amr_twin.bench import parts as pt


def test_a_part_s_time_excludes_the_wrapped_parts_it_calls(monkeypatch):
    ticks = iter(range(100))
    monkeypatch.setattr(pt, "timer", lambda: float(next(ticks)))
    timer = pt.PartTimer()
    inner = timer.wrap("inner", lambda: None)  # 1 tick inside
    outer = timer.wrap("outer", lambda: inner() or inner())
    outer()
    # outer: t 0 -> 5 (5 ticks), of which inner twice 1 tick each: 3 of its own
    assert dict(timer.cpu_s) == {"inner": 2.0, "outer": 3.0} and dict(timer.calls) == {
        "inner": 2,
        "outer": 1,
    }


def test_a_profile_s_parts_add_up_to_the_run_and_name_the_loop_s_pieces():
    code = (
        "from amr_twin.bench.parts import profile_parts, report; "
        "from amr_twin.model.config import load_config; "
        "import json; r = profile_parts(load_config(), 0.4, 1); print(json.dumps(r)); "
        "print('\\n'.join(report(r)))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=600, check=True
    ).stdout
    import json

    result = json.loads(out.splitlines()[0])
    for name in ("loop", "sensors"):
        (row,) = result[name]
        assert abs(sum(row["parts"].values()) - row["total"]) < 1e-9 and row["floor"] > 0
        assert (
            row["calls"]["WheelOdometry.publish"] > 0
            and row["calls"]["C chunks: mj_step and the C grid samplers"] > 0
        )
    assert "ImuSensor._publish_next" in result["sensors"][0]["parts"]
    assert "ImuSensor._publish_next" not in result["loop"][0]["parts"]
    assert any(line.startswith("sensors: ") for line in out.splitlines())
