"""The command line's process: what it sets before numpy loads."""

import os
import subprocess
import sys

import pytest

COUNT_THREADS = "import os, numpy; print(len(os.listdir('/proc/self/task')))"


def _threads(code: str, **env) -> int:
    base = {
        k: v
        for k, v in os.environ.items()  # what the caller (a Dask test before) exported
        if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
    }
    out = subprocess.run(
        [sys.executable, "-c", code],
        env={**base, **env},
        capture_output=True,
        text=True,
        check=True,
    )
    return int(out.stdout.split()[-1])


@pytest.mark.skipif(
    not os.path.isdir("/proc/self/task") or (os.cpu_count() or 1) < 2,
    reason="counts the threads of a process in /proc on a machine with 2 cores or more",
)
def test_the_command_line_starts_no_blas_threads_unless_asked():
    """numpy's OpenBLAS starts a worker per core that spin-waits (~0.1 s of CPU at import on 2
    cores): the command line's process runs it on its own thread, and a value the user exported
    wins."""
    assert _threads(COUNT_THREADS) > 1  # numpy alone: OpenBLAS's workers
    assert _threads("import amr_twin.cli.main; " + COUNT_THREADS) == 1
    assert _threads("import amr_twin.cli.main; " + COUNT_THREADS, OPENBLAS_NUM_THREADS="2") == 2


HEAVY = ("mujoco", "matplotlib", "rerun", "scipy", "numpy")


@pytest.mark.parametrize(
    "argv",
    [["--help"], ["run", "--help"], ["experiment", "--help"], ["sweep", "payload", "--help"]],
)
def test_help_imports_none_of_the_heavy_libraries(argv):
    """The command groups are module-level sub-apps imported at start-up: their modules keep the
    twin, the plots and the recorders behind the commands (start-up time is a benchmarked
    figure)."""
    code = (
        "import sys\nfrom amr_twin.cli.main import app\ntry:\n    app(sys.argv[1:])\nexcept "
        "SystemExit:\n    pass\n"
        f"print(sorted(m for m in {HEAVY!r} if m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code, *argv], capture_output=True, text=True, timeout=60, check=True
    )
    assert "Usage" in out.stdout
    assert out.stdout.strip().splitlines()[-1] == "[]"


def test_each_command_group_is_a_module_level_sub_app_of_module_level_commands():
    """No command defined inside a function (a ``register()`` closure): each group is the ``app`` of
    its module, each command a function of a module's top level."""
    from amr_twin.cli import experiment, main, run, sweep

    groups = {g.name: g.typer_instance for g in main.app.registered_groups}
    assert groups == {"run": run.app, "experiment": experiment.app, "sweep": sweep.app}
    commands = {
        (group, c.name or c.callback.__name__): c.callback
        for group, sub in (("", main.app), *groups.items())
        for c in sub.registered_commands
    }
    assert {name for group, name in commands if group == "experiment"} == {
        "chapter5",
        "faults",
        "fleet",
        "fusion",
        "navigation",
        "umbmark",
        "chapter5-attainable",
    }
    assert {name for group, name in commands if group == "run"} == {
        "linear",
        "angular",
        "motor",
        "stop",
        "goto",
    }
    for (group, name), callback in commands.items():
        original = getattr(callback, "__wrapped__", callback)
        assert "<locals>" not in original.__qualname__, f"{group} {name}: defined inside a function"
