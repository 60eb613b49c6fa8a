"""``amr-twin run goto --live``: the plan, the map, the costmap and the footprint reach a Foxglove client."""

from pathlib import Path
import sys

from foxglove_client import FoxgloveClient, start_cli

AMR_TWIN = str(Path(sys.executable).with_name("amr-twin"))
TOPICS = {"/plan": "nav_msgs/msg/Path", "/map": "nav_msgs/msg/OccupancyGrid",
          "/local_costmap/costmap": "nav_msgs/msg/OccupancyGrid",
          "/local_costmap/published_footprint": "geometry_msgs/msg/PolygonStamped"}


def test_goto_live_serves_the_plan_map_costmap_and_footprint():
    proc, url = start_cli(["run", "goto", "--goal", "-6,0,180", "--start=-9,0,0", "--localisation", "truth",
                           "--live", "--port", "0", "--rate", "0"], AMR_TWIN)
    try:
        with FoxgloveClient(url) as client:
            client.wait_for_channels(list(TOPICS), timeout_s=30.0)
            assert {t: client.channels[t]["schemaName"] for t in TOPICS} == TOPICS
            client.subscribe(list(TOPICS))
            got = client.pump(20.0, until=lambda: client.closed)
    finally:
        out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err[-2000:]
    seen = {topic for _t, topic, _ns, _payload in got}
    assert {"/plan", "/local_costmap/published_footprint", "/local_costmap/costmap"} <= seen, seen
