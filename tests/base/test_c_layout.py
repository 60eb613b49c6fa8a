"""The C helpers' struct layouts against their ctypes twins (amr_twin/base/c_layout.py)."""

import ctypes
import importlib
import shutil
from pathlib import Path

import pytest

from amr_twin.model.config import load_config
from amr_twin.sim import battery
from amr_twin.base import c_layout, native_build
from amr_twin.assembly.twin import Twin, TwinOptions

pytestmark = pytest.mark.skipif(
    shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler"
)

WRAPPERS = (
    "amr_twin.sim.actors",
    "amr_twin.sim.battery",
    "amr_twin.sim.collisions",
    "amr_twin.sim.grid_steps",
    "amr_twin.sim.rolling_resistance",
    "amr_twin.sim.tyres",
    "amr_twin.sensors.hall_edges",
    "amr_twin.sensors.imu_errors",
    "amr_twin.sensors.lidar_kernels",
)
"""Every module that opens a C helper (its ``C_SOURCE``)."""


def test_every_helper_loads_and_every_struct_of_its_table_is_registered():
    sources = {Path(importlib.import_module(m).C_SOURCE).resolve() for m in WRAPPERS}
    package = Path(native_build.__file__).resolve().parents[2]
    on_disk = {
        p.resolve()
        for folder in ("amr_twin/sim", "sensors")
        for p in (package / folder).glob("*.c")
    }
    assert sources == on_disk, "a C helper without its wrapper in WRAPPERS"
    with_structs = 0
    for source in sources:
        assert native_build.native_status(source) == "C", source.name
        table = c_layout.c_layouts(native_build.load_helper(source)) or {}
        assert set(table) == set(c_layout.registered(source)), source.name
        with_structs += bool(table)
    assert with_structs == 7


def _copy(tmp_path: Path, name: str, edit=lambda text: text) -> Path:
    """battery.c under another name (a helper of its own), edited."""
    source = tmp_path / name
    source.write_text(edit(battery.C_SOURCE.read_text()))
    return source


class _WithExtra(ctypes.Structure):
    """battery's _State with one more int after ``mode``."""

    _fields_ = [
        *battery._State._fields_[:13],
        ("extra", ctypes.c_int),
        *battery._State._fields_[13:],
    ]


def _status(source: Path, struct=battery._State) -> str:
    c_layout.register(source, battery_state=struct)
    return native_build.native_status(source)


def test_the_copy_matches_as_the_original_does(tmp_path):
    assert _status(_copy(tmp_path, "same.c")) == "C"


def test_a_field_added_on_the_python_side_is_found(tmp_path):
    assert battery._State._fields_[12][0] == "mode"
    with pytest.warns(RuntimeWarning, match="the Python twin runs instead"):
        status = _status(_copy(tmp_path, "py_extra.c"), _WithExtra)
    assert status == (
        "Python (py_extra.c: battery_state lacks the field 'extra' of its ctypes twin "
        "(_WithExtra in Python))"
    )


def _add_c_field(text: str, listed: bool = True) -> str:
    text = text.replace("    int mode[2];", "    int mode[2];\n    int extra;")
    listing = "AMR_FIELD(battery_state, mode), AMR_FIELD(battery_state, extra),"
    return text.replace("AMR_FIELD(battery_state, mode),", listing) if listed else text


def test_a_field_added_on_the_c_side_is_found(tmp_path):
    with pytest.warns(RuntimeWarning):
        status = _status(_copy(tmp_path, "c_extra.c", _add_c_field))
    assert "battery_state has a field 'extra' its ctypes twin lacks" in status
    assert status.startswith("Python (")


def test_a_field_added_in_c_but_not_in_its_table_is_found_by_the_offsets(tmp_path):
    with pytest.warns(RuntimeWarning):
        status = _status(_copy(tmp_path, "c_unlisted.c", lambda t: _add_c_field(t, listed=False)))
    assert "field 'ke' at byte 120 of 16 in C, at 112 of 16 in ctypes" in status


def test_a_retyped_field_is_found(tmp_path):
    with pytest.warns(RuntimeWarning):
        status = _status(
            _copy(
                tmp_path, "c_long.c", lambda t: t.replace("    int mode[2];", "    long mode[2];")
            )
        )
    assert "field 'mode' at byte 104 of 16 in C, at 104 of 8 in ctypes" in status


def test_a_helper_without_its_table_is_not_used(tmp_path):
    with pytest.warns(RuntimeWarning):
        status = _status(
            _copy(
                tmp_path, "no_table.c", lambda t: t.replace("AMR_LAYOUT(", "#define NO(...)\nNO(")
            )
        )
    assert status == "Python (no_table.c exports no amr_layout table for battery_state)"


def test_the_battery_falls_back_to_its_python_twin_on_a_mismatch(tmp_path, monkeypatch):
    source = _copy(tmp_path, "battery_mismatch.c", _add_c_field)
    c_layout.register(source, battery_state=battery._State)
    monkeypatch.setattr(battery, "C_SOURCE", source)
    with pytest.warns(
        RuntimeWarning, match="battery_mismatch.c: battery_state has a field 'extra'"
    ):
        twin = Twin(load_config(), TwinOptions(world="empty"))
    pack = twin.plant.battery
    assert pack.engine.startswith("Python (battery_mismatch.c: battery_state has a field 'extra'")
    soc0 = pack.soc
    twin.advance(1.0)
    assert 0.0 < soc0 - pack.soc < 1e-3  # the Python twin accounts


def test_a_field_appended_in_c_but_not_in_its_table_is_found_by_the_size(tmp_path):
    with pytest.warns(RuntimeWarning):
        status = _status(
            _copy(
                tmp_path,
                "c_tail.c",
                lambda t: t.replace("double charger_a;", "double charger_a; double extra;"),
            )
        )
    assert "battery_state is 208 bytes in C, 200 in ctypes" in status
