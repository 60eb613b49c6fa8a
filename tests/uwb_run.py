"""The 2 s UWB run that the recording tests write and read back (tests/recording/test_recording.py,
test_mcap_rosbags.py).

The twin drives straight at 0.5 m/s in the empty world with the UWB tag of the
default configuration (no IMU, no LiDAR), its capture attached, and writes the
recordings asked for.
"""

from pathlib import Path

from amr_twin.model.config import load_config
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.recording.rerun_capture import attach
from amr_twin.recording.rerun_log import record_run
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_mission

UWB_S = 2.0
"""Duration of the run, s."""


def record_uwb_run(out_dir: Path, rrd: bool = True, mcap: bool = True):
    """Run the twin with a UWB tag for :data:`UWB_S` and record it to ``out_dir``/uwb.rrd and
    uwb.mcap.

    Parameters
    ----------
    out_dir : Path
        An existing folder.
    rrd, mcap : bool
        Which recordings to write.

    Returns
    -------
    tuple
        ``(cfg, capture, paths)``: the configuration, the
        :class:`~amr_twin.recording.rerun_capture.Capture` and ``{"rrd": path, "mcap": path}`` of
        the files written.
    """
    cfg = load_config()
    options = TwinOptions(world="empty")
    twin = Twin(cfg, options)
    twin.add_sensor("uwb")
    capture = attach(twin)
    result = run_mission(cfg, [(0.0, Command("linear", speed_m_s=0.5))], UWB_S, options, twin=twin)
    paths = record_run(
        twin,
        rrd_path=out_dir / "uwb.rrd" if rrd else None,
        mcap_path=out_dir / "uwb.mcap" if mcap else None,
        result=result,
    )
    return cfg, capture, paths
