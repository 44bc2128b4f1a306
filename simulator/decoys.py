"""Static decoys in the scene (``decoys`` of a world file): bodies shaped and painted like a target car, and the
visibility cones the bounded-error box sensor tests (paper 004).

A decoy's cone has its vertex at the decoy and its axis at azimuth ``yaw`` tilted ``tilt`` from the vertical:
``a = (sin tilt cos yaw, sin tilt sin yaw, cos tilt)``, half aperture ``λ``; the paper draws the aperture 2λ in
[π/15, π/5] and tilts the axis by the aperture (``tilt = 2λ``, the default when the world file leaves it out).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["DECOY_CAR", "StaticDecoys", "build_decoys", "cone_axis"]


def cone_axis(yaw: float, tilt: float) -> np.ndarray:
    """Unit axis (3,) of a visibility cone at azimuth ``yaw`` tilted ``tilt`` from the vertical (rad)."""
    return np.array([math.sin(tilt) * math.cos(yaw), math.sin(tilt) * math.sin(yaw), math.cos(tilt)])


@dataclass(frozen=True)
class StaticDecoys:
    """The world's static decoys.

    Attributes
    ----------
    p_W : np.ndarray
        (M, 3) body centres (m).
    yaw : np.ndarray
        (M,) headings (rad).
    cone_axis_W : np.ndarray
        (M, 3) unit axes of the visibility cones.
    cone_half_angle : np.ndarray
        (M,) half apertures (rad).
    body_ids : np.ndarray
        (M,) PyBullet bodies.
    """

    p_W: np.ndarray
    yaw: np.ndarray
    cone_axis_W: np.ndarray
    cone_half_angle: np.ndarray
    body_ids: np.ndarray

    def __len__(self) -> int:
        return len(self.yaw)


DECOY_CAR = "sedan"  # the car type (vehicles/cars) whose body a decoy has


def build_decoys(specs: Sequence[object], scene: object, rgba: Sequence[float]) -> StaticDecoys | None:
    """Add a static body per ``decoys`` entry (sedan-sized, painted ``rgba``) to ``scene``; None without decoys."""
    if not specs:
        return None
    from vehicles.car.params import load_car

    car = load_car(DECOY_CAR)
    size = (car.length, car.width, car.height)
    p = np.array([d.position for d in specs], dtype=float)
    yaw = np.radians([d.yaw_deg for d in specs])
    half = np.radians([d.cone_half_angle_deg for d in specs])
    tilt = np.array([math.radians(d.tilt_deg) if d.tilt_deg is not None else 2.0 * h
                     for d, h in zip(specs, half, strict=True)])
    axis = np.array([cone_axis(y, g) for y, g in zip(yaw, tilt, strict=True)])
    bodies = np.array([scene.add_static_box(c, size, y, rgba) for c, y in zip(p, yaw, strict=True)], dtype=int)
    return StaticDecoys(p_W=p, yaw=yaw, cone_axis_W=axis, cone_half_angle=half, body_ids=bodies)
