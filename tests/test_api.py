"""The public API (amr_twin/__init__.py): at most 20 names, each there, none loaded before it is
asked for."""

import subprocess
import sys

import amr_twin


def test_star_import_gives_at_most_20_names_and_each_resolves():
    scope: dict = {}
    exec("from amr_twin import *", scope)
    names = sorted(k for k in scope if not k.startswith("__"))
    assert names == sorted(amr_twin.__all__) and len(names) <= 20
    assert all(scope[name] is not None for name in names)


def test_the_experiments_registry_comes_with_the_built_ins():
    assert {"chapter5", "payload", "fusion", "umbmark"} <= set(amr_twin.EXPERIMENTS.names())
    assert {"imu", "lidar", "uwb"} <= set(amr_twin.SENSORS.names())
    assert set(amr_twin.FIRMWARES.names()) >= {"faithful", "improved", "avr"}


def test_an_unknown_name_is_an_attribute_error():
    try:
        amr_twin.Nothing  # noqa: B018
    except AttributeError as exc:
        assert "Nothing" in str(exc)
    else:
        raise AssertionError("amr_twin.Nothing resolved")


def test_importing_the_package_loads_nothing_heavy():
    code = "import sys, amr_twin; print(sorted(m for m in ('numpy', 'mujoco') if m in sys.modules))"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True
    )
    assert out.stdout.strip() == "[]"
