"""amr-twin client: the fig. 3.2 menu under a pseudo-terminal, the twin at 20x real time."""

import sys
from pathlib import Path

import pytest

pexpect = pytest.importorskip("pexpect")

AMR_TWIN = Path(sys.executable).with_name("amr-twin")


def test_menu_linear_then_stop_then_exit():
    child = pexpect.spawn(str(AMR_TWIN), ["client", "--rate", "20", "--firmware", "faithful"],
                          encoding="utf-8", timeout=30, env={"TERM": "dumb", "NO_COLOR": "1",
                                                             "COLUMNS": "120", "PATH": "/usr/bin:/bin"})
    try:
        child.expect("Linear motion")
        child.expect("choice: ")
        child.sendline("1")
        child.expect(r"linear speed \[m/s\]: ")
        child.sendline("0.5")
        child.expect(r"sent wheel_Command \[1, 38\.19719, 1, 38\.19719\]")
        child.expect(r"wheel0_Vel \(left \)\s+(\d+\.\d+) RPM")  # first sample after ~1.7 s
        assert 25.0 < float(child.match.group(1)) < 55.0
        child.sendline("9")  # the prompt may be buried under speed lines: an unknown choice
        child.expect("unknown choice")
        child.sendline("1")
        child.expect(r"linear speed \[m/s\]: ")
        child.sendline("30")
        child.expect("ERROR: linear velocity not valid")
        child.sendline("3")
        child.expect(r"sent wheel_Command \[0, 0\.00000, 0, 0\.00000\]")
        child.sendline("0")
        child.expect("exit at t=")
        child.expect(pexpect.EOF)
    finally:
        child.close()
    assert child.exitstatus == 0
