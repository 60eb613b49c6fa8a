"""The live options of ``amr-twin run`` and ``amr-twin client``, checked before the work."""

import json
import socket

import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.cli.live_options import live_option_args

pytest.importorskip("foxglove")
runner = CliRunner()
QUICK = ["--duration-s", "0.2", "--world", "empty", "--rate", "0", "--port", "0"]


def test_bare_live_means_foxglove_wherever_it_stands():
    kinds = ("linear", "stop")
    assert live_option_args(["--live"]) == ["--live=foxglove"]
    assert live_option_args(["--live", "linear", "--port", "0"], kinds) == [
        "--live=foxglove",
        "linear",
        "--port",
        "0",
    ]
    assert live_option_args(["linear", "--live", "rerun"], kinds) == ["linear", "--live", "rerun"]
    assert live_option_args(["linear", "--live", "--json"], kinds) == [
        "linear",
        "--live=foxglove",
        "--json",
    ]
    assert live_option_args(["--", "--live"]) == ["--", "--live"]
    # any other word is the value, refused naming the modes (it was taken for an extra argument)
    assert live_option_args(["stop", "--live", "bogus"], kinds) == ["stop", "--live", "bogus"]
    for args in (
        ["run", "stop", "--live", "bogus"],
        ["run", "--live", "bogus", "stop"],
        ["client", "--live", "bogus"],
    ):
        res = runner.invoke(app, args)
        assert (
            res.exit_code == 2
            and res.stderr.strip()
            == "error: --live 'bogus': must be one of foxglove, rerun (a bare --live is foxglove)"
        )


@pytest.mark.parametrize(
    "args",
    [
        ["linear", "--speed-m-s", "0.3", "--live", *QUICK, "--json"],
        ["--live", "linear", "--speed-m-s", "0.3", *QUICK, "--json"],
    ],
    ids=["after the kind", "before the kind"],
)
def test_live_run_serves_and_reports_as_a_plain_run(args):
    result = runner.invoke(app, ["run", *args])
    assert result.exit_code == 0, result.output
    assert "live: Foxglove WebSocket server on ws://127.0.0.1:" in result.stderr
    info = json.loads(result.stdout)
    assert info["wheel_command"] == pytest.approx([1, 22.918, 1, 22.918], abs=1e-3)


def test_live_rerun_run_prints_its_stream_and_viewer():
    result = runner.invoke(app, ["run", "stop", "--live", "rerun", *QUICK, "--web-port", "0"])
    assert result.exit_code == 0, result.output
    assert "rerun+http://127.0.0.1:" in result.stderr and "/?url=rerun%2Bhttp" in result.stderr


@pytest.mark.parametrize(
    "args,message",
    [
        (["--rate", "2"], "--rate is an option of --live"),
        (["--port", "9000"], "--port is an option of --live"),
        (["--live=bogus"], "--live 'bogus': must be one of foxglove, rerun"),
        (["--live", "--host", "999.1.1.1"], "--host 999.1.1.1: not an address ("),
        (["--live", "--rate", "-1"], "--rate -1.0: must be a finite number in [0, 1000]"),
        (["--live", "--rate", "nan"], "--rate nan: must be a finite number"),
        (["--live", "--port", "70000"], "--port 70000: must be in [0, 65535]"),
        (["--live", "--web-port", "9091"], "--web-port is the Rerun web viewer's"),
        (["--live", "rerun", "--host", "0.0.0.0"], "--host is the Foxglove server's"),
        (["--host", "0.0.0.0"], "--host is an option of --live"),
    ],
)
def test_bad_live_options_refused_in_one_line(args, message):
    result = runner.invoke(app, ["run", "linear", "--speed-m-s", "0.3", *args])
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0]


def test_a_port_in_use_refused_before_the_model_is_built():
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        result = runner.invoke(
            app, ["run", "linear", "--speed-m-s", "0.3", "--live", "--port", str(port)]
        )
        client = runner.invoke(app, ["client", "--live", "--port", str(port)])
    for res in (result, client):
        assert res.exit_code == 2
        assert f"--port {port}: cannot listen on 127.0.0.1:{port}" in res.stderr
        assert "live: Foxglove" not in res.stderr
