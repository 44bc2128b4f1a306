"""A car as a PyBullet multibody: a chassis box on four sphere wheels, Ackermann-steered front knuckles.

Links (indices): 0 front-left knuckle (revolute about body z), 1 front-left wheel (revolute about y), 2 front-right
knuckle, 3 front-right wheel, 4 rear-left wheel, 5 rear-right wheel. The base frame is the centre of mass, midway
between the axles at ``cog_height``; wheel centres sit at (+-L/2, +-track/2, r - cog_height). Wheels are spheres (one
contact point each: no edge chatter at 240 Hz) with Coulomb friction ``tyre_friction``; the chassis box starts at
``ground_clearance``. There is no suspension.

Ackermann steering for a bicycle angle delta (rear-axle turn radius R = L / tan delta):
    tan delta_left = L tan(delta) / (L - (t/2) tan delta),   tan delta_right = L tan(delta) / (L + (t/2) tan delta).
Rolling wheel speeds for a centre-of-mass speed v (slip angle beta = atan(tan(delta)/2), rear-axle speed
v_r = v cos beta, tau = tan delta):
    rear:  v_r (1 -+ (t/2) tau / L) / r,    front:  v_r sqrt((1 -+ (t/2) tau / L)^2 + tau^2) / r    (left -, right +).
Drive: the rear wheels track their rolling speeds with velocity motors limited to ``max_drive_torque / 2`` each while
the front wheels roll free; braking and holding: all four track with ``max_brake_torque / 4`` each.
"""

from __future__ import annotations

import math

import numpy as np
import pybullet as p

from vehicles.car.params import CarParams

__all__ = ["CarBody", "ackermann_angles", "chassis_box", "wheel_speeds"]

STEER_JOINTS = (0, 2)
WHEEL_JOINTS = (1, 3, 4, 5)  # FL, FR, RL, RR
_HUB_RADIUS = 0.05  # m; knuckle collision sphere (inside the wheel; gives the knuckle a proper inertia)
_Z_TO_Y = (math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4))  # visual cylinder axis z -> body y
_STEER_TOL = 1e-4  # rad; steering target changes below this are not re-sent
_SPEED_TOL = 1e-3  # m/s; speed target changes below this are not re-sent
_BODY_RGBA = (0.75, 0.1, 0.1, 1.0)
_WHEEL_RGBA = (0.1, 0.1, 0.1, 1.0)


def chassis_box(params: CarParams) -> tuple[list[float], float]:
    """The chassis box in the body frame: (half extents (3,) m, height of its centre above the centre of mass (m)).

    Length x width x (height - ground_clearance), its floor at ``ground_clearance`` above the ground.
    """
    box_h = params.height - params.ground_clearance
    half = [0.5 * params.length, 0.5 * params.width, 0.5 * box_h]
    return half, params.ground_clearance + 0.5 * box_h - params.cog_height


def ackermann_angles(delta: float, wheelbase: float, track: float) -> tuple[float, float]:
    """(left, right) front-wheel steering angles (rad) for the bicycle angle ``delta`` (rad)."""
    tau = math.tan(delta)
    return (math.atan(wheelbase * tau / (wheelbase - 0.5 * track * tau)),
            math.atan(wheelbase * tau / (wheelbase + 0.5 * track * tau)))


def wheel_speeds(v: float, delta: float, params: CarParams) -> np.ndarray:
    """(4,) rolling angular speeds (rad/s) of the FL, FR, RL, RR wheels for centre-of-mass speed ``v`` (m/s)."""
    return np.array(_wheel_speed_list(v, delta, params))


def _wheel_speed_list(v: float, delta: float, params: CarParams) -> list[float]:
    """:func:`wheel_speeds` as a list of floats (the same products, without the array)."""
    tau = math.tan(delta)
    v_r = v * math.cos(math.atan(0.5 * tau))
    q = 0.5 * params.track * tau / params.wheelbase
    rl, rr = 1.0 - q, 1.0 + q
    k = v_r / params.wheel_radius
    return [k * math.hypot(rl, tau), k * math.hypot(rr, tau), k * rl, k * rr]


class CarBody:
    """One car in a PyBullet world.

    Parameters
    ----------
    client_id : int
        PyBullet physics client.
    params : CarParams
        The car type.
    p_xy : np.ndarray
        Spawn position of the centre of mass in the ground plane (2,) (m).
    yaw : float
        Spawn heading (rad).
    ground_z : float
        Height of the ground under the car (m).
    """

    def __init__(self, client_id: int, params: CarParams, p_xy: np.ndarray, yaw: float, ground_z: float = 0.0) -> None:
        self.client_id, self.params = client_id, params
        c, par = client_id, params
        L, t, r, h = par.wheelbase, par.track, par.wheel_radius, par.cog_height
        half, box_z = chassis_box(par)
        chassis = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, collisionFramePosition=[0, 0, box_z],
                                         physicsClientId=c)
        chassis_vis = p.createVisualShape(p.GEOM_BOX, halfExtents=half, visualFramePosition=[0, 0, box_z],
                                          rgbaColor=_BODY_RGBA, physicsClientId=c)
        wheel = p.createCollisionShape(p.GEOM_SPHERE, radius=r, physicsClientId=c)
        wheel_vis = p.createVisualShape(p.GEOM_CYLINDER, radius=r, length=0.6 * r, visualFrameOrientation=_Z_TO_Y,
                                        rgbaColor=_WHEEL_RGBA, physicsClientId=c)
        hub = p.createCollisionShape(p.GEOM_SPHERE, radius=_HUB_RADIUS, physicsClientId=c)
        z_w = r - h
        corners = {"fl": (0.5 * L, 0.5 * t), "fr": (0.5 * L, -0.5 * t), "rl": (-0.5 * L, 0.5 * t),
                   "rr": (-0.5 * L, -0.5 * t)}
        m_base = par.mass - 4 * par.wheel_mass - 2 * par.hub_mass
        masses = [par.hub_mass, par.wheel_mass, par.hub_mass, par.wheel_mass, par.wheel_mass, par.wheel_mass]
        shapes = [hub, wheel, hub, wheel, wheel, wheel]
        visuals = [-1, wheel_vis, -1, wheel_vis, wheel_vis, wheel_vis]
        positions = [[*corners["fl"], z_w], [0, 0, 0], [*corners["fr"], z_w], [0, 0, 0], [*corners["rl"], z_w],
                     [*corners["rr"], z_w]]
        parents = [0, 1, 0, 3, 0, 0]  # 0 = base, k = link k - 1
        axes = [[0, 0, 1], [0, 1, 0], [0, 0, 1], [0, 1, 0], [0, 1, 0], [0, 1, 0]]
        q0 = p.getQuaternionFromEuler([0.0, 0.0, float(yaw)])
        self.body_id = p.createMultiBody(
            baseMass=m_base, baseCollisionShapeIndex=chassis, baseVisualShapeIndex=chassis_vis,
            basePosition=[float(p_xy[0]), float(p_xy[1]), ground_z + h], baseOrientation=q0,
            linkMasses=masses, linkCollisionShapeIndices=shapes, linkVisualShapeIndices=visuals,
            linkPositions=positions, linkOrientations=[[0, 0, 0, 1]] * 6,
            linkInertialFramePositions=[[0, 0, 0]] * 6, linkInertialFrameOrientations=[[0, 0, 0, 1]] * 6,
            linkParentIndices=parents, linkJointTypes=[p.JOINT_REVOLUTE] * 6, linkJointAxis=axes,
            physicsClientId=c)
        p.changeDynamics(self.body_id, -1, linearDamping=0.0, angularDamping=0.0, lateralFriction=0.3,
                         physicsClientId=c)
        for j in WHEEL_JOINTS:
            p.changeDynamics(self.body_id, j, lateralFriction=par.tyre_friction, rollingFriction=par.rolling_friction,
                             spinningFriction=0.01 * r, jointDamping=0.0, physicsClientId=c)
        for j in STEER_JOINTS:
            p.changeDynamics(self.body_id, j, jointLowerLimit=-par.max_steer - 0.2, jointUpperLimit=par.max_steer + 0.2,
                             jointDamping=0.0, physicsClientId=c)
        self._drive = [0.0, 0.0, 0.5 * par.max_drive_torque, 0.5 * par.max_drive_torque]  # wheel motor forces
        self._brake = [0.25 * par.max_brake_torque] * 4
        self._steer_force = [par.steer_torque] * 2
        self._sent: tuple[float, float, bool] | None = None
        self.apply(0.0, 0.0, braking=True)

    def apply(self, steer: float, speed: float, braking: bool) -> None:
        """Motor targets for bicycle steering angle ``steer`` (rad) and centre-of-mass speed ``speed`` (m/s).

        PyBullet keeps motor targets between steps, so targets within ``_STEER_TOL`` / ``_SPEED_TOL`` of the last
        ones sent are not sent again.
        """
        par, c = self.params, self.client_id
        last = self._sent
        steer_changed = last is None or abs(steer - last[0]) > _STEER_TOL
        if steer_changed:
            left, right = ackermann_angles(steer, par.wheelbase, par.track)
            p.setJointMotorControlArray(self.body_id, STEER_JOINTS, p.POSITION_CONTROL, targetPositions=[left, right],
                                        forces=self._steer_force, physicsClientId=c)
        if steer_changed or abs(speed - last[1]) > _SPEED_TOL or braking != last[2]:
            p.setJointMotorControlArray(self.body_id, WHEEL_JOINTS, p.VELOCITY_CONTROL,
                                        targetVelocities=_wheel_speed_list(speed, steer, par),
                                        forces=self._brake if braking else self._drive, physicsClientId=c)
            self._sent = (steer, speed, braking)

    def read(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(p_W (3,) m, q_WB (4,) xyzw, v_W (3,) m/s, omega_W (3,) rad/s) of the centre of mass."""
        x = np.array(self.state_row())
        return x[0:3], x[3:7], x[7:10], x[10:13]

    def state_row(self) -> tuple[float, ...]:
        """The 13 numbers of :meth:`read` in one flat tuple (p_W, q_WB, v_W, omega_W), as PyBullet reports them."""
        (pos, q), (v, w) = (p.getBasePositionAndOrientation(self.body_id, physicsClientId=self.client_id),
                            p.getBaseVelocity(self.body_id, physicsClientId=self.client_id))
        return pos + q + v + w

    def steer_angles(self) -> tuple[float, float]:
        """Measured (left, right) knuckle angles (rad)."""
        states = p.getJointStates(self.body_id, STEER_JOINTS, physicsClientId=self.client_id)
        return float(states[0][0]), float(states[1][0])
