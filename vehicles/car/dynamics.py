"""How one car of a fleet moves under its driver's commands: a PyBullet multibody, or a kinematic bicycle carrying a
box.

Both run once per physics tick in the run loop's phase 1 (:meth:`actuate`, before ``p.stepSimulation()``) and report
the car's state after the step (:meth:`state_row`).

``physics`` (:class:`PhysicsDynamics`): the :class:`~vehicles.car.body.CarBody` multibody (chassis, four wheel joints,
motors, Ackermann steering, tyre contacts) tracks a speed reference that integrates the commanded acceleration,
v_ref <- clip(v_ref + a / f_phys, 0, v_max), re-anchored to within ``_REF_BAND`` of the measured speed at each driver
update (so wheel slip or a blocked car cannot wind it up), and a steering reference that follows the command at most
``max_steer_rate``.

``kinematic`` (:class:`KinematicDynamics`): a :class:`~vehicles.car.bicycle.KinematicBicycle` advanced by one physics
step per tick, then its :class:`~vehicles.car.box_body.CarBoxBody` placed at the new pose, before PyBullet steps, so
the step's contacts and every raycast after it see the box where the state says the car is. The model is integrated
at the physics rate, not in closed form between driver updates: the steering angle ramps at ``max_steer_rate`` within
a driver period (no closed form for the heading), the box must be placed every tick anyway, and explicit Euler at
1/240 s is exact in the speed (constant acceleration between updates) and, at constant speed and steering angle, in
the heading, while the position then runs on the polygon inscribed in a circle larger than the true one by
(omega dt)^2 / 24 (< 1e-6 relative in town driving). It costs a few microseconds per car and tick.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import numpy as np

from vehicles.car.bicycle import KinematicBicycle
from vehicles.car.body import CarBody
from vehicles.car.box_body import CarBoxBody, yaw_quaternion
from vehicles.car.driver_config import DriveCommand
from vehicles.car.params import CarParams

__all__ = ["CAR_DYNAMICS", "CarDynamics", "KinematicDynamics", "PhysicsDynamics", "make_dynamics"]

_REF_BAND = 1.0  # m/s; largest lead of the physics car's speed reference over its measured speed


class CarDynamics(Protocol):
    """One car's motion, as the fleet steps it."""

    body_id: int

    def actuate(self, command: DriveCommand) -> None:
        """Run-loop phase 1: act on the driver's last command for one physics step."""

    def state_row(self) -> tuple[float, ...]:
        """The 13 numbers p_W (m), q_WB (x, y, z, w), v_W (m/s), omega_W (rad/s) of the centre of mass."""

    def on_driver_update(self, speed: float) -> None:
        """Called after the driver updated its command from the measured forward ``speed`` (m/s)."""


class PhysicsDynamics:
    """A physics car: speed and steering references at the physics rate become :class:`CarBody` motor targets.

    Parameters: those of :func:`make_dynamics` after ``kind``.
    """

    def __init__(self, client_id: int, params: CarParams, p_xy: np.ndarray, yaw: float, physics_hz: int) -> None:
        self.params, self.dt = params, 1.0 / physics_hz
        self.body = CarBody(client_id, params, p_xy, yaw)
        self.body_id = self.body.body_id
        self.v_ref = 0.0
        self.steer_ref = 0.0
        self._steer_step = params.max_steer_rate * self.dt  # largest steering reference change per step (rad)

    def actuate(self, command: DriveCommand) -> None:
        if command.hold:
            self.v_ref = 0.0
        else:
            self.v_ref = min(max(self.v_ref + command.accel * self.dt, 0.0), self.params.max_speed)
        step = self._steer_step
        self.steer_ref += min(max(command.steer - self.steer_ref, -step), step)
        self.body.apply(self.steer_ref, self.v_ref, braking=command.hold or command.accel < 0.0)

    def state_row(self) -> tuple[float, ...]:
        return self.body.state_row()

    def on_driver_update(self, speed: float) -> None:
        v = max(speed, 0.0)
        self.v_ref = min(max(self.v_ref, v - _REF_BAND), v + _REF_BAND)


class KinematicDynamics:
    """A kinematic car: a :class:`KinematicBicycle` moving a :class:`CarBoxBody`, integrated in steps of
    1 / physics_hz from rest.

    Parameters: those of :func:`make_dynamics` after ``kind``.
    """

    def __init__(self, client_id: int, params: CarParams, p_xy: np.ndarray, yaw: float, physics_hz: int) -> None:
        self.dt = 1.0 / physics_hz
        self.model = KinematicBicycle(params, p_xy, yaw)
        self.box = CarBoxBody(client_id, params, p_xy, yaw)
        self.body_id = self.box.body_id
        self._q = yaw_quaternion(self.model.yaw)

    def actuate(self, command: DriveCommand) -> None:
        m = self.model
        m.step(command, self.dt)
        self._q = yaw_quaternion(m.yaw)
        self.box.place(m.x, m.y, self._q)

    def state_row(self) -> tuple[float, ...]:
        m = self.model
        vx, vy, yaw_rate = m.rates()
        return (m.x, m.y, self.box.z, *self._q, vx, vy, 0.0, 0.0, 0.0, yaw_rate)

    def on_driver_update(self, speed: float) -> None:
        pass


CAR_DYNAMICS: dict[str, Callable[..., CarDynamics]] = {"physics": PhysicsDynamics, "kinematic": KinematicDynamics}
"""The car dynamics by the name world files give them (``ground_vehicles[i].dynamics``)."""


def make_dynamics(kind: str, client_id: int, params: CarParams, p_xy: np.ndarray, yaw: float,
                  physics_hz: int) -> CarDynamics:
    """The dynamics named ``kind`` of one car.

    Parameters
    ----------
    kind : str
        A key of :data:`CAR_DYNAMICS`.
    client_id : int
        PyBullet physics client.
    params : CarParams
        The car type.
    p_xy, yaw : np.ndarray, float
        Spawn position of the centre of mass (2,) (m) and heading (rad); the car starts at rest.
    physics_hz : int
        Physics rate (Hz).
    """
    try:
        cls = CAR_DYNAMICS[kind]
    except KeyError:
        raise ValueError(f"car dynamics must be one of {sorted(CAR_DYNAMICS)}, got {kind!r}") from None
    return cls(client_id, params, p_xy, yaw, physics_hz)
