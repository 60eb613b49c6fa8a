#!/usr/bin/env bash
# Regenerate docs/img/rerun_viewer.png: a recorded twin run opened in the native Rerun viewer.
#
# Works on a machine without a screen or GPU: the viewer draws into a virtual X server (Xvfb)
# through Mesa's software Vulkan driver (lavapipe), and its own --screenshot-to option writes
# the PNG once the recording has loaded. Debian packages needed (none of them by CI or the tests):
#
#   apt-get install -y --no-install-recommends xvfb xauth xdotool mesa-vulkan-drivers libvulkan1 \
#     imagemagick
#
# Usage: docs/img/make_rerun_screenshot.sh [PYTHON]
#   PYTHON: the interpreter of the environment where amr-twin is installed (default: python3);
#           the `rerun` viewer is the one next to it (rerun-sdk ships it).
#
# What it records (10 simulated seconds, IMU and LiDAR on): linear 0.5 m/s, then at 5 s the
# chapter 5 clockwise rotation (-60 deg/s about an ICC 1 m to the right), in the default
# warehouse. The view is the recording's own default blueprint, with two changes for the still
# picture: the time cursor follows the end of the data (the default plays from the start) and
# the 3D camera looks at the robot's path instead of the whole warehouse.
set -euo pipefail

repo="$(cd "$(dirname "$0")/../.." && pwd)"
python="${1:-python3}"
rerun="$(dirname "$(command -v "$python")")/rerun"
out="$repo/docs/img/rerun_viewer.png"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# 1. The recording (.rrd) and a blueprint (.rbl) for the still picture.
"$python" - "$work" <<'EOF'
import sys
from pathlib import Path

import numpy as np
import rerun.blueprint as rrb

from amr_twin import (Command, Twin, TwinOptions, attach_capture, load_config, record_run,
                      run_mission)

work = Path(sys.argv[1])
cfg, options = load_config(), TwinOptions(sensors=("imu", "lidar"))
twin = Twin(cfg, options)
attach_capture(twin)
steps = [(0.0, Command("linear", speed_m_s=0.5)),
         (5.0, Command("angular", speed_deg_s=-60.0, icc_m=-1.0))]
result = run_mission(cfg, steps, 10.0, options, twin=twin)
record_run(twin, rrd_path=work / "run.rrd", result=result)

# Camera: behind and above the centre of the path, looking at it.
xy = result.series.pose[:, :2]
centre_m = np.append((xy.min(axis=0) + xy.max(axis=0)) / 2, 0.3)
eye = rrb.EyeControls3D(position=centre_m + np.array([-3.6, -1.4, 2.6]), look_target=centre_m,
                        eye_up=[0.0, 0.0, 1.0])
plots = [rrb.TimeSeriesView(origin=f"wheels/{w}", name=f"{w} wheel RPM") for w in ("left", "right")]
plots += [rrb.TimeSeriesView(origin="duty", name="PWM counts"), rrb.TimeSeriesView(origin="imu", name="IMU")]
rrb.Blueprint(
    rrb.Horizontal(rrb.Vertical(rrb.Spatial3DView(origin="world", name="twin", eye_controls=eye),
                                rrb.TextLogView(origin="commands", name="commands"), row_shares=[4, 1]),
                   rrb.Vertical(*plots), column_shares=[3, 2]),
    rrb.TimePanel(timeline="sim_time", play_state="following", state="collapsed"),
    collapse_panels=True,
).save("amr_twin", work / "still.rbl")
EOF

# 2. The viewer in a virtual screen; it writes the screenshot and quits. HOME and
#    XDG_RUNTIME_DIR point at the temporary folder so that nothing is left behind.
mkdir -p "$work/home" && chmod 700 "$work/home"
export HOME="$work/home" XDG_RUNTIME_DIR="$work/home" WGPU_BACKEND=vulkan
"$rerun" analytics disable > /dev/null 2>&1
# The pointer would hover over the 3D view and open a tooltip: xdotool keeps moving it to
# the empty top bar while the viewer loads.
timeout 300 xvfb-run -a -s "-screen 0 1600x1000x24" sh -c \
  'for i in $(seq 40); do xdotool mousemove 1100 8 mousemove 1100 10; sleep 0.5; done & exec "$@"' sh \
  "$rerun" --renderer vulkan --bind 127.0.0.1 --port auto --window-size 1600x1000 \
  --screenshot-to "$work/shot.png" "$work/run.rrd" "$work/still.rbl" > "$work/viewer.log" 2>&1 \
  || { tail -20 "$work/viewer.log"; exit 1; }

# 3. The viewer saves at twice the window size: scale to 1600 px wide, 256 colours (~300 KB).
convert "$work/shot.png" -resize 1600x -dither None -colors 256 -strip "PNG8:$out"
echo "wrote $out ($(stat -c %s "$out") bytes)"
