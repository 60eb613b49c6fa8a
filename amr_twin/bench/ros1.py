"""The ROS 1 path's figures of ``amr-twin bench --suites``, each measured in fresh child processes.

Reasons and measurements: docs/reference/speed.md#amr_twinbenchros1."""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from amr_twin.bench.twin import BENCH_START

REPEATS = 5
SIM_S = 20.0
PACED_S = 60.0
SUBSCRIBED = (
    "/clock",
    "/tf",
    "/tf_static",
    "/odom",
    "/joint_states",
    "/scan",
    "/imu/data_raw",
    "/imu/mag",
)
"""The topics the bridge figure's recorder takes (each costs a socket write a message in the twin's
process)."""
WARM_UPS = 5
"""Short bridged runs at most before ``rosbag record -a`` subscribes to the twin's topics."""
COMMANDS = 40
"""wheel_Command frames written by the serial latency figure's host thread."""


def _child(mode: str, sim_s: float, env: dict) -> dict:
    out = subprocess.run(
        [sys.executable, "-m", "amr_twin.bench.ros1", mode, str(sim_s)],
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    if out.returncode != 0:
        raise RuntimeError(f"bench ros1 {mode}: {out.stderr.strip().splitlines()[-1:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def _twin(sensors: bool = True, firmware: str = "faithful", params=None):
    from amr_twin.model.config import load_config
    from amr_twin.assembly.twin import Twin, TwinOptions
    from amr_twin.assembly.command import Command

    twin = Twin(
        load_config(),
        TwinOptions(
            firmware=firmware,
            sensors=("imu", "lidar") if sensors else (),
            start_xy_yaw=BENCH_START,
            firmware_params=params,
            visuals=False,
        ),
    )  # as the command builds it
    Command("linear", speed_m_s=0.7).send(twin)
    return twin


def _measure(mode: str, sim_s: float) -> dict:
    """One child's figure (see the module notes)."""
    if mode == "serial":
        return _serial_latency(sim_s)
    twin = _twin()
    session = None
    if mode != "plain":
        from amr_twin.controllers.diff_drive import DiffDriveNode
        from amr_twin.live.pacer import Pacer
        from amr_twin.ros1.session import Ros1Options, Ros1Session

        from amr_twin.ros1.session import pacer_tick_us

        rate = 1.0 if mode == "paced" else 0.0
        pacer = Pacer(twin, rate, pacer_tick_us(rate))
        DiffDriveNode(twin.bus, twin.clock, twin.client)
        session = Ros1Session(twin, pacer, Ros1Options(), say=lambda line: None)
    cpu0, wall0 = time.process_time(), time.perf_counter()
    twin.advance(sim_s)
    out = {
        "cpu_s": time.process_time() - cpu0,
        "wall_s": time.perf_counter() - wall0,
        "sim_s": sim_s,
    }
    if session is not None:
        pacer.close()
        session.close()
        out.update(messages=session.bridge.out.messages, writes=session.bridge.out.writes)
    return out


def _serial_latency(sim_s: float) -> dict:
    import random
    import threading

    from amr_twin.controllers.firmware import AvrParams
    from amr_twin.ros.rosserial_frame import frame, serialize_float64_multiarray

    path = os.path.join(tempfile.mkdtemp(prefix="amr-twin-bench-"), "ttyACM0")
    twin = _twin(sensors=False, firmware="avr", params=AvrParams(serial_pty=path))
    fw = twin.firmware
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
    data = frame(100, serialize_float64_multiarray([1.0, 40.0, 1.0, 40.0]))
    writes: list[float] = []
    arrivals: list[int] = []
    read = fw.serial.read

    def read_and_note():  # the instant the twin takes the host's bytes, simulated us
        got = read()
        if got:
            arrivals.append(twin.clock.now_us)
        return got

    fw.serial.read = read_and_note
    rng = random.Random(0)

    def host():
        time.sleep(0.5)
        for _ in range(COMMANDS):
            time.sleep(rng.uniform(0.05, 0.25))
            writes.append(time.perf_counter())
            os.write(fd, data)

    thread = threading.Thread(target=host)
    thread.start()
    twin.advance(sim_s)
    thread.join()
    os.close(fd)
    delays = [fw.pacer.wall_of(t) - w for w, t in zip(writes, arrivals)]
    fw.close()
    return {
        "delays_ms": [d * 1e3 for d in delays],
        "frame_bytes": len(data),
        "matched": len(delays) == len(writes),
    }


def _bag_messages(path: str) -> int:
    """Messages in a bag, but the latched ones (read with the rosbags library)."""
    from rosbags.highlevel import AnyReader

    with AnyReader([Path(path)]) as reader:
        return sum(c.msgcount for c in reader.connections if c.topic not in ("/tf_static",))


def _recorder(env: dict, folder: str, name: str, topics) -> subprocess.Popen:
    """``rosbag record`` of ``topics`` (``-a``: every topic) into ``folder/name.bag``."""
    return subprocess.Popen(
        ["rosbag", "record", "-O", os.path.join(folder, f"{name}.bag"), *topics, f"__name:={name}"],
        env=env,
        cwd=folder,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def _stop(rec: subprocess.Popen) -> None:
    rec.send_signal(2)
    rec.wait(20)


def _recording_all(master_uri: str, name: str) -> bool:
    """Whether the recorder ``name`` subscribes to the twin's ground truth (``-a`` subscribes to a
    topic once the master lists it)."""
    import xmlrpc.client

    subs = xmlrpc.client.ServerProxy(master_uri).getSystemState("/bench")[2][1]
    return any(t == "/twin/ground_truth" and f"/{name}" in nodes for t, nodes in subs)


def _pairs(env: dict, repeats: int, say, what: str) -> tuple[list, list, list]:
    """Interleaved plain and bridged children: their CPU times and the bridged ones' figures."""
    plain, bridged, runs = [], [], []
    for r in range(repeats):
        say(f"ROS 1 bridge, {what}, repeat {r + 1} of {repeats}")
        plain.append(_child("plain", SIM_S, env)["cpu_s"])
        runs.append(_child("bridge", SIM_S, env))
        bridged.append(runs[-1]["cpu_s"])
    return plain, bridged, runs


def ros1_figures(repeats: int = REPEATS, progress=None) -> dict:
    """The figures of the module notes; ``ros1_skipped`` says why when Debian's ROS 1 (or, for the
    serial figure, the AVR toolchain) is absent."""
    from amr_twin.controllers.avr_build import missing_tools
    from amr_twin.ros1.installation import missing
    from amr_twin.ros1.master import start_roscore
    from amr_twin.ros.rosserial import frame_time_us

    problem = missing()
    if problem:
        return {"ros1_skipped": problem}
    say = progress or (lambda text: None)
    master = start_roscore()
    env = dict(os.environ, ROS_MASTER_URI=master.uri, ROS_IP="127.0.0.1")
    out: dict = {}
    folder = tempfile.mkdtemp(prefix="amr-twin-bench-bag-")
    rec = _recorder(env, folder, "bench_record", SUBSCRIBED)
    try:
        time.sleep(1.0)
        plain, bridged, runs = _pairs(env, repeats, say, "recorder of its topics")
        messages = statistics.median(r["messages"] for r in runs)
        out.update(
            ros1_bridge_ratio=statistics.median(b / p for b, p in zip(bridged, plain)),
            ros1_bridge_cpu_s=statistics.median(bridged),
            ros1_plain_cpu_s=statistics.median(plain),
            ros1_bridge_messages_per_sim_s=messages / SIM_S,
            ros1_bridge_writes_per_sim_s=statistics.median(r["writes"] for r in runs) / SIM_S,
            ros1_bridge_us_per_message=statistics.median(
                (b - p) / r["messages"] * 1e6 for b, p, r in zip(bridged, plain, runs)
            ),
            ros1_scenario=f"chapter 5 run 3 with sensors, {SIM_S:g} s, full speed, rosbag record "
            f"of {' '.join(SUBSCRIBED)}; ros1_bridge_all_*: rosbag record -a",
        )
        say(f"ROS 1 bridge paced at --rate 1 for {PACED_S:g} s")
        paced = _child("paced", PACED_S, env)
        out["ros1_paced_sim_per_wall"] = paced["sim_s"] / paced["wall_s"]
        _stop(rec)
        kept = _bag_messages(os.path.join(folder, "bench_record.bag"))
        out["ros1_bridge_recorded"] = (
            f"{kept} of {sum(r['messages'] for r in runs) + paced['messages']}"
        )
        rec = _recorder(env, folder, "bench_record_all", ["-a"])
        time.sleep(1.0)
        for _ in range(WARM_UPS):  # the twin's topics listed, so that -a subscribes to them
            _child("paced", 2.0, env)
            if _recording_all(master.uri, "bench_record_all"):
                break
        else:
            raise RuntimeError("bench ros1: rosbag record -a did not subscribe to the twin")
        plain, bridged, runs = _pairs(env, repeats, say, "rosbag record -a")
        out.update(
            ros1_bridge_all_ratio=statistics.median(b / p for b, p in zip(bridged, plain)),
            ros1_bridge_all_cpu_s=statistics.median(bridged),
            ros1_bridge_all_plain_cpu_s=statistics.median(plain),
            ros1_bridge_all_messages_per_sim_s=statistics.median(r["messages"] for r in runs)
            / SIM_S,
            ros1_bridge_all_writes_per_sim_s=statistics.median(r["writes"] for r in runs) / SIM_S,
        )
    finally:
        if rec.poll() is None:
            _stop(rec)
        master.stop()
    avr = missing_tools()
    if avr:
        out["ros1_serial_skipped"] = avr
        return out
    say("the board's serial port on a pseudo-terminal: wheel_Command latency")
    serial = _child("serial", 10.0, dict(os.environ))
    delays = serial["delays_ms"]
    out.update(
        ros1_serial_latency_ms=statistics.median(delays),
        ros1_serial_latency_max_ms=max(delays),
        ros1_serial_frame_ms=frame_time_us(serial["frame_bytes"], 115200) / 1000,
        ros1_serial_commands=len(delays) if serial["matched"] else f"{len(delays)} (unmatched)",
    )
    return out


if __name__ == "__main__":
    print(json.dumps(_measure(sys.argv[1], float(sys.argv[2]))))
