"""A fleet's .rrd: valid to ``rerun rrd verify``, each robot's bodies, track, scans and plots
under its own entity path."""

import collections
import subprocess
import sys

import pytest

from fleet_run import STARTS, record_fleet

ROBOTS = [f"amr-{i}" for i in range(1, len(STARTS) + 1)]


@pytest.fixture(scope="module")
def rrd(tmp_path_factory):
    return record_fleet(tmp_path_factory.mktemp("fleet"))[2]


def test_rerun_verifies_it(rrd, tmp_path):
    def verify(path):
        return subprocess.run(
            [sys.executable, "-m", "rerun", "rrd", "verify", str(path)],
            capture_output=True,
            text=True,
            timeout=300,
        )

    assert verify(rrd).returncode == 0
    broken = tmp_path / "broken.rrd"
    broken.write_bytes(rrd.read_bytes()[: rrd.stat().st_size // 2])
    assert verify(broken).returncode != 0  # the check can fail


def test_each_robot_under_its_entity_path(rrd):
    from rerun.chunk import RrdReader

    rows = collections.Counter()
    for chunk in RrdReader(str(rrd)).stream().to_chunks():
        rows[str(chunk.entity_path)] += chunk.num_rows
    for name in ROBOTS:
        for path in (
            f"/world/bodies/{name}/base_link",
            f"/world/{name}/scan",
            f"/{name}/electrics/battery/voltage_v",
            f"/{name}/wheels/left/true_rpm",
            f"/{name}/imu/accel",
        ):
            assert rows[path] > 0, path
        track = [p for p in rows if p.startswith(f"/world/{name}/trajectory/true/")]
        assert track, name
    assert rows["/world/bodies/amr-1/base_link"] == rows["/world/bodies/amr-3/base_link"]


def test_the_same_run_twice_gives_the_same_recordings(tmp_path):
    """The .mcap byte for byte; the .rrd the same data (``rerun rrd compare --unordered``: Rerun
    chunks what it is given as its threads run)."""
    paths = [record_fleet(tmp_path / name, duration_s=1.0)[1:] for name in ("a", "b")]
    (mcap_a, rrd_a), (mcap_b, rrd_b) = paths
    assert mcap_a.read_bytes() == mcap_b.read_bytes()
    done = subprocess.run(
        [sys.executable, "-m", "rerun", "rrd", "compare", "--unordered", str(rrd_a), str(rrd_b)],
        capture_output=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]
