"""Closed-form inertia of an X-frame quadrotor built from simple solids.

The body is modelled as a solid box hub at the centre of mass, four point masses (motor + propeller) at the rotor hubs
and four thin rods (arms) from the centre to the hubs along the X diagonals. Each part's principal moments:

.. math::

    I^{box}_{xx} = \\tfrac{m}{12}(b_y^2 + b_z^2), \\quad
    I^{rotors}_{xx} = \\sum_i m_r y_i^2 = 2 m_r L^2 \\;(\\text{X layout: } y_i^2 = L^2/2), \\quad
    I^{rotors}_{zz} = 4 m_r L^2,

    I^{rod}_{zz} = \\tfrac{m_a L^2}{3}, \\quad I^{rod}_{xx} = \\tfrac{m_a L^2}{6}\\ \\text{(each rod, at 45 deg)},

with ``b`` the full box edge lengths. Products of inertia vanish by the frame's symmetry.
"""

from __future__ import annotations

__all__ = ["x_frame_inertia"]


def x_frame_inertia(*, hub_mass: float, hub_size: tuple[float, float, float], rotor_mass: float,
                    arm_length: float, arm_mass: float = 0.0) -> tuple[float, float, float]:
    """Principal moments of inertia (kg m^2) of a hub box + 4 point rotors + 4 thin arms.

    Parameters
    ----------
    hub_mass : float
        Mass of the central box (kg).
    hub_size : tuple of float
        Full edge lengths of the central box along body x, y, z (m).
    rotor_mass : float
        Mass of one motor with its propeller, lumped at the hub (kg).
    arm_length : float
        Centre-to-hub distance (m).
    arm_mass : float
        Mass of one arm, a thin rod from the centre to the hub (kg).

    Returns
    -------
    tuple of float
        ``(I_xx, I_yy, I_zz)`` in kg m^2.
    """
    bx, by, bz = hub_size
    hub = (hub_mass * (by**2 + bz**2) / 12.0, hub_mass * (bx**2 + bz**2) / 12.0, hub_mass * (bx**2 + by**2) / 12.0)
    rot_xy = 2.0 * rotor_mass * arm_length**2
    rot_z = 4.0 * rotor_mass * arm_length**2
    arm_xy = 4.0 * arm_mass * arm_length**2 / 6.0
    arm_z = 4.0 * arm_mass * arm_length**2 / 3.0
    return (hub[0] + rot_xy + arm_xy, hub[1] + rot_xy + arm_xy, hub[2] + rot_z + arm_z)
