"""A rigid body's mass properties (:class:`Inertial`), the textbook inertias of a solid box,
cylinder and sphere about their centres, and parts summed by the parallel-axis theorem
(:func:`combine`); kg, m, kg m^2."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Inertial:
    """Mass properties of one link: mass (kg), centre of mass (m, (3,)), inertia about it (kg m^2,
    (3, 3))."""

    mass_kg: float
    com_m: np.ndarray
    inertia_kg_m2: np.ndarray

    def diag(self) -> tuple[float, float, float, float, float, float]:
        """(ixx, iyy, izz, ixy, ixz, iyz)."""
        i = self.inertia_kg_m2
        return (i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2])


def box_inertia(extents, mass_kg: float) -> np.ndarray:
    """(3, 3) inertia of a solid box of ``extents`` (a, b, c) m about its centre, kg m^2."""
    a, b, c = (float(e) for e in extents)
    return np.diag(
        [
            mass_kg * (b * b + c * c) / 12.0,
            mass_kg * (a * a + c * c) / 12.0,
            mass_kg * (a * a + b * b) / 12.0,
        ]
    )


def cylinder_inertia(radius_m: float, height_m: float, mass_kg: float) -> np.ndarray:
    """(3, 3) inertia of a solid cylinder about its centre, axis along z, kg m^2."""
    across = mass_kg * (3.0 * radius_m**2 + height_m**2) / 12.0
    return np.diag([across, across, 0.5 * mass_kg * radius_m**2])


def sphere_inertia(radius_m: float, mass_kg: float) -> np.ndarray:
    """(3, 3) inertia of a solid sphere about its centre, kg m^2."""
    return np.eye(3) * (0.4 * mass_kg * radius_m**2)


def combine(parts: list[Inertial]) -> Inertial:
    """Sum of several rigid parts (parallel-axis theorem)."""
    mass = sum(p.mass_kg for p in parts)
    com = sum(p.mass_kg * p.com_m for p in parts) / mass
    inertia = np.zeros((3, 3))
    for p in parts:
        d = p.com_m - com
        inertia += p.inertia_kg_m2 + p.mass_kg * (d @ d * np.eye(3) - np.outer(d, d))
    return Inertial(mass, com, inertia)
