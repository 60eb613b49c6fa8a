#!/usr/bin/env bash
# Regenerate docs/img/live_rerun_web_viewer.png: the twin streamed live (`--live rerun`) into Rerun's
# web viewer, served by the twin itself, opened in headless Chromium.
#
# Works on a machine without a screen or GPU: Chromium draws with its software rasterizer
# (SwiftShader) and is driven over the DevTools protocol (the `websockets` package of the dev
# extras). Debian package needed (not by CI or the tests):
#
#   apt-get install -y chromium
#
# Usage: docs/img/make_live_screenshot.sh [PYTHON]
#   PYTHON: the interpreter of the environment where amr-twin is installed (default: python3).
#
# What it streams: the square mission (experiments/missions/square.yaml, 14 simulated s, IMU and
# LiDAR on) in the warehouse at 2x real time, through the same LiveSession as `amr-twin run
# --mission experiments/missions/square.yaml --sensors --live rerun`; the browser connects as the
# run starts. The software rasterizer ingests slowly, so the server is kept up after the run until
# the viewer has drawn the whole stream; the view is the stream's own default blueprint.
set -euo pipefail

repo="$(cd "$(dirname "$0")/../.." && pwd)"
python="${1:-python3}"
out="$repo/docs/img/live_rerun_web_viewer.png"
command -v chromium > /dev/null || { echo "chromium is not installed (apt-get install -y chromium)" >&2; exit 1; }

"$python" - "$out" "$repo" <<'EOF'
import base64
import json
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

from websockets.sync.client import connect

from amr_twin import Twin, TwinOptions, load_config, run_mission
from amr_twin.assembly.mission import load_mission_file
from amr_twin.live.session import LiveOptions, LiveSession


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


out, repo = Path(sys.argv[1]), Path(sys.argv[2])
plan = load_mission_file(repo / "experiments/missions/square.yaml")
cfg, options = load_config(), TwinOptions(sensors=("imu", "lidar"), start_xy_yaw=None)
twin = Twin(cfg, options)
session = LiveSession(twin, LiveOptions(mode="rerun", port=0, web_port=0, rate=2.0))

profile = tempfile.mkdtemp()
devtools = free_port()
chrome = subprocess.Popen(["chromium", "--headless=new", "--no-sandbox", "--enable-unsafe-swiftshader",
                           "--use-angle=swiftshader", "--window-size=1600,1000", f"--remote-debugging-port={devtools}",
                           f"--user-data-dir={profile}", "about:blank"],
                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
try:
    for _ in range(200):
        try:
            pages = json.load(urllib.request.urlopen(f"http://127.0.0.1:{devtools}/json/list"))
            break
        except OSError:
            time.sleep(0.1)
    page = next(p for p in pages if p["type"] == "page")
    with connect(page["webSocketDebuggerUrl"], max_size=None) as ws:
        def call(n, method, **params):
            ws.send(json.dumps({"id": n, "method": method, "params": params}))
            while True:
                reply = json.loads(ws.recv(timeout=60))
                if reply.get("id") == n:
                    return reply

        call(1, "Page.navigate", url=session.sink.web_url)
        run_mission(cfg, plan.steps, plan.duration_s, options, twin=twin)  # 7 s of wall time
        session.close()
        time.sleep(60)  # the software rasterizer catches up with the stream
        shot = call(2, "Page.captureScreenshot", format="png")
        out.write_bytes(base64.b64decode(shot["result"]["data"]))
finally:
    chrome.kill()
    chrome.wait()
    shutil.rmtree(profile, ignore_errors=True)
print(f"wrote {out} ({out.stat().st_size} bytes)")
EOF
