"""The one set of set-points guidance returns and the quadrotor flies: validation, conversion, the former names."""

import numpy as np
import pytest

from interfaces.setpoints import (FACE_VELOCITY_MIN_SPEED, FlightSetpoint, PositionSetpoint, Setpoint,
                                  UnicycleSetpoint, VelocitySetpoint)


@pytest.mark.parametrize("value", ["1.0", None, float("nan"), float("inf"), np.array([1.0, 2.0]), 1 + 2j],
                         ids=["str", "none", "nan", "inf", "array", "complex"])
def test_unicycle_rejects_what_is_not_one_finite_number_and_names_the_field(value):
    with pytest.raises(ValueError, match="UnicycleSetpoint.heading_rate must be a finite number"):
        UnicycleSetpoint(speed=1.0, heading_rate=value, altitude=10.0)


@pytest.mark.parametrize("make, match", [
    (lambda: UnicycleSetpoint(speed=-0.5, heading_rate=0.0, altitude=10.0), "UnicycleSetpoint.speed must be >= 0"),
    (lambda: VelocitySetpoint(v_W=[1.0, 2.0]), "VelocitySetpoint.v_W"),
    (lambda: VelocitySetpoint(v_W=[1.0, np.inf, 0.0]), "VelocitySetpoint.v_W"),
    (lambda: VelocitySetpoint(v_W=[1.0, 2.0, 0.0], yaw=np.nan), "VelocitySetpoint.yaw"),
    (lambda: PositionSetpoint(p_W=[[1.0, 2.0, 3.0]] * 2), "PositionSetpoint.p_W"),
    (lambda: PositionSetpoint(p_W=[1.0, 2.0, 3.0], yaw="north"), "PositionSetpoint.yaw"),
])
def test_invalid_setpoints_rejected(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_numbers_of_any_real_type_become_floats_and_vectors_read_only_copies():
    sp = UnicycleSetpoint(speed=np.float32(2.5), heading_rate=np.int64(0), altitude=np.array(30.0))
    assert (sp.speed, sp.heading_rate, sp.altitude) == (2.5, 0.0, 30.0)
    assert all(type(v) is float for v in (sp.speed, sp.heading_rate, sp.altitude))
    v = np.array([1, 2, 3])
    vel = VelocitySetpoint(v_W=v, yaw=np.float64(0.25))
    v[0] = 9
    assert vel.v_W.dtype == float and vel.v_W.tolist() == [1.0, 2.0, 3.0] and type(vel.yaw) is float
    assert not vel.v_W.flags.writeable and PositionSetpoint(p_W=(0, 0, 5)).yaw is None


def test_guidance_setpoints_are_flight_setpoints_and_keep_their_recorded_names():
    uni = UnicycleSetpoint(speed=1.0, heading_rate=0.1, altitude=20.0)
    vel = VelocitySetpoint(v_W=[0.0, 1.0, 0.0])
    assert isinstance(uni, Setpoint) and isinstance(vel, Setpoint)
    assert not isinstance(PositionSetpoint(p_W=[0.0, 0.0, 1.0]), Setpoint)
    assert all(isinstance(sp, FlightSetpoint) for sp in (uni, vel, PositionSetpoint(p_W=[0.0, 0.0, 1.0])))
    assert (type(uni).__name__, type(vel).__name__) == ("UnicycleSetpoint", "VelocitySetpoint")
    assert FACE_VELOCITY_MIN_SPEED == 0.5


def test_former_modules_re_export_the_same_types():
    from autonomy.guidance import setpoints, types
    from interfaces import state
    from vehicles.quadrotor import commands

    assert (setpoints.UnicycleSetpoint, setpoints.VelocitySetpoint) == (UnicycleSetpoint, VelocitySetpoint)
    assert (commands.UnicycleCommand, commands.VelocityCommand, commands.PositionCommand) == (
        UnicycleSetpoint, VelocitySetpoint, PositionSetpoint)
    assert commands.FlightCommand == FlightSetpoint and setpoints.Setpoint == Setpoint
    assert (types.OwnState, types.TargetEstimate, types.TeammateState) == (
        state.OwnState, state.TargetEstimate, state.TeammateState)
