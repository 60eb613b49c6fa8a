"""amr-twin's public API: build the twin, run it, record it, navigate, and add plug-ins.

The names load on first use (PEP 562), so ``import amr_twin`` stays light.
Reference: docs/reference/api.md.
"""

from __future__ import annotations

import importlib

_WHERE = {
    "load_config": "amr_twin.model.config",
    "Twin": "amr_twin.assembly.twin",
    "TwinOptions": "amr_twin.assembly.twin",
    "ParameterSpace": "amr_twin.calibration.uncertainty",
    "Command": "amr_twin.assembly.command",
    "run_command": "amr_twin.recording.run",
    "run_mission": "amr_twin.recording.run",
    "Actor": "amr_twin.model.actors",
    "attach_recorder": "amr_twin.recording.recorder",
    "attach_capture": "amr_twin.recording.rerun_capture:attach",
    "record_run": "amr_twin.recording.rerun_log",
    "navigate": "amr_twin.navigation.navigation_run",
    "NavigationOptions": "amr_twin.navigation.stack",
    "LocalController": "amr_twin.navigation.interfaces",
    "Twist2D": "amr_twin.navigation.interfaces",
    "SENSORS": "amr_twin.sensors.catalog",
    "FIRMWARES": "amr_twin.controllers.firmware",
    "CONTROLLERS": "amr_twin.navigation.registries",
    "LOCALISATIONS": "amr_twin.navigation.registries",
    "EXPERIMENTS": "amr_twin.experiments.catalogue:experiments()",
}
"""Each public name and where it lives: ``module``, ``module:attribute`` or ``module:function()``
(the experiments' registry with the built-ins registered)."""

__all__ = list(_WHERE)


def __getattr__(name: str):
    if name not in _WHERE:
        raise AttributeError(f"module 'amr_twin' has no attribute {name!r}")
    module, _, attribute = _WHERE[name].partition(":")
    value = getattr(importlib.import_module(module), (attribute or name).removesuffix("()"))
    value = value() if attribute.endswith("()") else value
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
