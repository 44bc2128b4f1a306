"""A car as one rigid box in PyBullet, placed by a kinematic model: no wheels, joints, motors or contact forces.

The box is the physics car's chassis (:func:`~vehicles.car.body.chassis_box`): length x width x (height -
ground_clearance), its floor at ``ground_clearance``, its base frame at the centre of mass (midway between the axles,
``cog_height`` above the ground). Sensors' occlusion raycasts, the camera's colour detector (base link -1, as on the
physics car) and contact checks therefore see the same shape as the physics car's body.

The body has mass 0 and maximal coordinates (a plain rigid body, not a one-link multibody): PyBullet's step costs
about 0.13 ms per 1000 such boxes against 0.8 ms for 1000 fixed multibodies, which city traffic would otherwise pay
every physics tick. It is static to Bullet: gravity and contacts never move it and it adds no rows to the constraint
solver unless a dynamic body (a UAV, a physics car) touches it, which then meets it as it would a
building. :meth:`CarBoxBody.place` teleports it; rays cast afterwards see it at once (no physics step needed).
"""

from __future__ import annotations

import math

import numpy as np
import pybullet as p

from vehicles.car.body import chassis_box
from vehicles.car.params import CarParams

__all__ = ["CarBoxBody", "yaw_quaternion"]

_BODY_RGBA = (0.75, 0.1, 0.1, 1.0)


def yaw_quaternion(yaw: float) -> tuple[float, float, float, float]:
    """Quaternion (x, y, z, w) of a rotation by ``yaw`` (rad) about the world z axis."""
    return 0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw)


class CarBoxBody:
    """One car's box in a PyBullet world; parameters as those of :class:`~vehicles.car.body.CarBody` (client, car
    type, initial centre-of-mass position (2,) m and heading rad, ground height m)."""

    def __init__(self, client_id: int, params: CarParams, p_xy: np.ndarray, yaw: float, ground_z: float = 0.0) -> None:
        self.client_id, self.params = client_id, params
        self.z = ground_z + params.cog_height  # height of the centre of mass (m)
        half, box_z = chassis_box(params)
        col = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, collisionFramePosition=[0, 0, box_z],
                                     physicsClientId=client_id)
        vis = p.createVisualShape(p.GEOM_BOX, halfExtents=half, visualFramePosition=[0, 0, box_z],
                                  rgbaColor=_BODY_RGBA, physicsClientId=client_id)
        self.body_id = p.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=col, baseVisualShapeIndex=vis,
                                         basePosition=[float(p_xy[0]), float(p_xy[1]), self.z],
                                         baseOrientation=yaw_quaternion(float(yaw)), useMaximalCoordinates=True,
                                         physicsClientId=client_id)
        # asleep: Bullet recomputes the bounding box of every awake object at every step, and a static body, never
        # put to sleep by the simulation, would be awake for good (about 85 us per 1000 boxes and step here). Moving
        # the box (place) still updates its bounding box at once, and awake bodies still collide with it.
        p.changeDynamics(self.body_id, -1, activationState=p.ACTIVATION_STATE_SLEEP, physicsClientId=client_id)

    def place(self, x: float, y: float, q_WB: tuple[float, float, float, float]) -> None:
        """Move the box's centre of mass to (x, y) (m) at its fixed height, oriented ``q_WB`` (x, y, z, w)."""
        p.resetBasePositionAndOrientation(self.body_id, (x, y, self.z), q_WB, physicsClientId=self.client_id)
