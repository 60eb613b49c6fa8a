"""What the robot stands on: its wheels' tyres and caster balls, the normal contact force on each
(from the constraint forces of the last step), and a wheel taken off the ground (a fault).

Part of the physics layer (``PHYSICS_LAYER``): reads the contacts and constraint forces of
MjData."""

from __future__ import annotations

import numpy as np

from amr_twin.model.robot_spec import WHEELS

PHYSICS_LAYER = True


class Support:
    """The support geoms of one robot in ``model`` and ``data``: ``geoms`` by name (``wheel_left``,
    ``wheel_right``, ``caster_fl``, ... in that order) -> geom id."""

    def __init__(self, model, data, geoms: dict[str, int]):
        self.model, self.data, self.geoms = model, data, geoms
        self.of_geom = [-1] * model.ngeom
        """(ngeom,) index of each geom in :attr:`geoms` (0-5), -1 for the others."""
        for i, g in enumerate(geoms.values()):
            self.of_geom[g] = i
        self._contype = {
            g: (int(model.geom_contype[g]), int(model.geom_conaffinity[g])) for g in geoms.values()
        }

    def normal_forces_n(self) -> np.ndarray:
        """(6,) normal contact force on the wheels L, R and casters fl, fr, rl, rr, N (0 when
        lifted).

        From the constraint forces of the last step (the first row of each contact is its
        normal force, for pyramidal-free elliptic cones and for frictionless contacts).
        """
        d = self.data
        out = [0.0] * len(self.geoms)
        if d.ncon:  # a handful of contacts: plain Python, in contact order (~5 us, ~30 with numpy)
            con, lut, force = d.contact, self.of_geom, d.efc_force
            for (g1, g2), adr in zip(con.geom.tolist(), con.efc_address.tolist()):
                k = max(lut[g1], lut[g2])
                if k >= 0 and adr >= 0:  # -1: a contact not in the constraints
                    out[k] += force.item(adr)
        return np.array(out)

    def loads_n(self) -> dict[str, float]:
        """Normal contact force on each wheel and caster ball, N (0 when lifted)."""
        return dict(zip(self.geoms, self.normal_forces_n().tolist()))

    def lift_wheel(self, wheel: int, lifted: bool) -> None:
        """Take ``wheel`` off the ground (its tyre touches nothing), or put it back."""
        g = self.geoms[f"wheel_{WHEELS[wheel]}"]
        contype, conaffinity = (0, 0) if lifted else self._contype[g]
        self.model.geom_contype[g], self.model.geom_conaffinity[g] = contype, conaffinity
