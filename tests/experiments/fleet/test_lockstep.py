"""The twins' VDA 5050 timestamps read back as simulated seconds."""

from amr_twin.experiments.fleet.lockstep import EPOCH, sim_seconds
from amr_twin.fleet.protocol import Stamper


def test_a_timestamp_on_the_twins_clock_reads_back_to_the_millisecond():
    stamper = Stamper("amr-1", EPOCH)
    for t in (0.0, 0.02, 127.2, 3599.999, 86400.5):
        assert sim_seconds(stamper.timestamp(t)) == round(t, 3)
