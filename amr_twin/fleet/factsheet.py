"""The vehicle's VDA 5050 2.0 factsheet (the specification's chapter 7) from the parameter file.

Dimensions from the model (chassis length, the wheels' outer faces, the LiDAR's top), speeds and
accelerations from ``navigation.limits``, the drive wheels and casters from ``wheel`` and
``caster``, the load capacity from ``payload.max_mass_kg``, the actions of
:mod:`amr_twin.fleet.actions` (the parameters of pick and drop: :data:`ACTION_DETAILS`).
"""

from __future__ import annotations

from amr_twin.fleet.actions import EDGE_ACTIONS, INSTANT_ACTIONS, NODE_ACTIONS
from amr_twin.fleet.adapter import STATE_PERIOD_S


def _parameter(key: str, kind: str, description: str, optional: bool = True) -> dict:
    return {"key": key, "valueDataType": kind, "description": description, "isOptional": optional}


_LOAD_ID = _parameter("loadId", "STRING", "the load's id, reported in state.loads")
ACTION_DETAILS = {
    "pick": {
        "actionDescription": "a worker puts the load on the deck (no load handling device): the "
        "vehicle stands for payload.handling_time_s, then carries its weight",
        "actionParameters": [
            _parameter("weight", "NUMBER", "the load's mass, kg (> 0, at most maxLoadMass)", False),
            _LOAD_ID,
            _parameter("loadType", "STRING", "reported in state.loads"),
            _parameter("stationType", "STRING", "read, not used"),
        ],
        "resultDescription": "load on the deck",
    },
    "drop": {
        "actionDescription": "a worker takes the load off the deck",
        "actionParameters": [_parameter("loadId", "STRING", "if given, the load carried")],
        "resultDescription": "deck empty",
    },
    "startCharging": {
        "actionDescription": "connects the charger; only at a charging station of the map "
        "(state.information chargingStation), the vehicle standing; it drives nowhere until "
        "stopCharging",
    },
    "stopCharging": {"actionDescription": "disconnects the charger"},
}
"""What the factsheet says of the actions beyond their scopes."""


def factsheet(cfg) -> dict:
    """The factsheet's body (without the header) of the robot ``cfg`` describes (SI units)."""
    from amr_twin.navigation.footprint import robot_footprint
    from amr_twin.navigation.stack import robot_top_m

    lim, wheel, caster = cfg.navigation.limits, cfg.wheel, cfg.caster
    footprint = robot_footprint(cfg)
    wheels = [
        {
            "type": "DRIVE",
            "isActiveDriven": True,
            "isActiveSteered": False,
            "position": {"x": 0.0, "y": side * wheel.separation_m / 2},
            "diameter": 2 * wheel.radius_m,
            "width": wheel.width_m,
        }
        for side in (1, -1)
    ]
    wheels += [
        {
            "type": "CASTER",
            "isActiveDriven": False,
            "isActiveSteered": False,
            "position": {"x": sx * caster.x_m, "y": sy * caster.y_m},
            "diameter": caster.ball_diameter_m,
            "width": caster.ball_diameter_m,
        }
        for sx in (1, -1)
        for sy in (1, -1)
    ]
    outline = [{"x": float(x), "y": float(y)} for x, y in footprint.corners_xy_m()]
    scopes = {}
    for scope, names in (
        ("INSTANT", INSTANT_ACTIONS),
        ("NODE", NODE_ACTIONS),
        ("EDGE", EDGE_ACTIONS),
    ):
        for name in names:
            scopes.setdefault(name, []).append(scope)
    return {
        "typeSpecification": {
            "seriesName": "amr-twin",
            "seriesDescription": "the thesis' differential-drive warehouse AMR, as its MuJoCo twin",
            "agvKinematic": "DIFF",
            "agvClass": "CARRIER",
            "maxLoadMass": cfg.payload.max_mass_kg,
            "localizationTypes": ["NATURAL"],
            "navigationTypes": ["AUTONOMOUS"],
        },
        "physicalParameters": {
            "speedMin": 0.0,
            "speedMax": lim.max_v_m_s,
            "accelerationMax": lim.accel_m_s2,
            "decelerationMax": lim.decel_m_s2,
            "heightMax": robot_top_m(cfg),
            "width": 2 * footprint.half_width_m,
            "length": cfg.chassis.length_m,
        },
        "protocolLimits": {
            "maxStringLens": {},
            "maxArrayLens": {},
            "timing": {
                "minOrderInterval": 0.0,
                "minStateInterval": 0.0,
                "defaultStateInterval": STATE_PERIOD_S,
            },
        },
        "protocolFeatures": {
            "optionalParameters": [
                {"parameter": "order.nodes.nodePosition", "support": "REQUIRED"},
                {"parameter": "order.nodes.nodePosition.theta", "support": "SUPPORTED"},
                {
                    "parameter": "order.nodes.nodePosition.allowedDeviationXy",
                    "support": "SUPPORTED",
                },
                {
                    "parameter": "order.nodes.nodePosition.allowedDeviationTheta",
                    "support": "SUPPORTED",
                },
            ],
            "agvActions": [
                {"actionType": name, "actionScopes": sorted(s), **ACTION_DETAILS.get(name, {})}
                for name, s in sorted(scopes.items())
            ],
        },
        "agvGeometry": {
            "wheelDefinitions": wheels,
            "envelopes2d": [{"set": "default", "polygonPoints": outline}],
        },
        "loadSpecification": {"loadPositions": []},
    }
