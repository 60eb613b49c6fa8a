"""The fleet bench: every size timed, its cost per robot-second against the first size and the
whole world's real-time factor consistent with it."""

from amr_twin.bench.fleet import fleet_figures
from amr_twin.model.config import load_config


def test_fleet_figures_relate_cost_ratio_and_real_time_factor():
    out = fleet_figures(load_config(), counts=(1, 2), rounds=1, sim_s=0.5)
    cost, ratio, rtf = out["fleet_ms_per_robot_s"], out["fleet_ratio_to_1"], out["fleet_rtf"]
    assert set(cost) == set(ratio) == set(rtf) == {1, 2}
    assert ratio[1] == 1.0 and abs(ratio[2] - cost[2] / cost[1]) < 0.02
    for n in (1, 2):  # n robots for one simulated second cost n times the per-robot figure
        assert abs(rtf[n] - 1000.0 / (cost[n] * n)) <= 0.02 * rtf[n]
