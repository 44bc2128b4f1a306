"""Guidance inputs, outputs, configurations and keep-out geometry."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from autonomy.guidance.fast_mpc import FastMpcConfig
from autonomy.guidance.keepout import footprint_distance, keepout_ellipse, nearby_keepouts
from autonomy.guidance.nmpc_config import NmpcConfig
from autonomy.guidance.vector_field import VectorFieldConfig
from interfaces.setpoints import UnicycleSetpoint, VelocitySetpoint
from interfaces.state import OwnState, TargetEstimate, TeammateState
from worlds.geometry import Building


@pytest.mark.parametrize("cls, field, value", [
    (NmpcConfig, "standoff_radius", -1.0), (NmpcConfig, "horizon", 1), (NmpcConfig, "solver", "newton"),
    (NmpcConfig, "direction", 0), (VectorFieldConfig, "nominal_speed", 0.0), (VectorFieldConfig, "team_size", 0),
    (FastMpcConfig, "v_min", -1.0), (FastMpcConfig, "separation_mode", "circle"),
], ids=lambda v: str(v) if not isinstance(v, type) else v.__name__)
def test_config_rejects_bad_value_and_names_field(cls, field, value):
    with pytest.raises(ValueError, match=field):
        cls(**{field: value})


def test_setpoints_validate():
    with pytest.raises(ValueError, match="speed"):
        UnicycleSetpoint(speed=-1.0, heading_rate=0.0, altitude=10.0)
    with pytest.raises(ValueError, match="v_W"):
        VelocitySetpoint(v_W=[1.0, 2.0])
    sp = VelocitySetpoint(v_W=[1, 2, 3])
    assert sp.v_W.shape == (3,) and sp.yaw is None


def test_target_and_teammate_prediction():
    tgt = TargetEstimate(t=2.0, p_W=[10.0, 0.0, 0.0], v_W=[1.0, -2.0, 0.0])
    np.testing.assert_allclose(tgt.predict_xy(5.0), [13.0, -6.0])
    plan = np.array([[2.0, 0.0], [4.0, 0.0], [6.0, 2.0]])
    tm = TeammateState(id=1, t=0.0, p_W=[0, 0, 50], v_W=[4, 0, 0], plan_p_W=plan, plan_dt=0.5)
    got = tm.predict_xy(np.array([0.25, 1.0, 1.25, 2.0]))
    np.testing.assert_allclose(got, [[1.0, 0.0], [4.0, 0.0], [5.0, 1.0], [8.0, 4.0]])
    cv = TeammateState(id=2, t=1.0, p_W=[0, 0, 50], v_W=[0, 3, 0])
    np.testing.assert_allclose(cv.predict_xy(np.array([3.0])), [[0.0, 6.0]])
    with pytest.raises(ValueError, match="plan_p_W"):
        TeammateState(id=0, t=0.0, p_W=[0, 0, 0], v_W=[0, 0, 0], plan_p_W=np.zeros((3, 4)))
    own = OwnState(t=0.0, p_W=[0, 0, 0], v_W=[0.0, 0.1, 0], yaw=1.0)
    assert own.course(min_speed=0.5) == 1.0


@settings(max_examples=60, deadline=None)
@given(x=st.floats(-80, 80), y=st.floats(-80, 80), yaw=st.floats(-np.pi, np.pi), margin=st.floats(0, 10))
def test_keepout_ellipse_is_conservative(x, y, yaw, margin):
    """Outside the ellipse ⇒ at least ``margin`` from the footprint."""
    b = Building.cuboid((5.0, -3.0), (40.0, 16.0, 30.0), yaw=yaw)
    e = keepout_ellipse(b, margin)
    if e.h(np.array([x, y])) >= 0:
        assert footprint_distance(b, (x, y)) >= margin - 1e-9


def test_footprint_distance_closed_form_and_selection():
    b = Building.cuboid((0.0, 0.0), (20.0, 10.0, 30.0))
    assert footprint_distance(b, (15.0, 0.0)) == pytest.approx(5.0)
    assert footprint_distance(b, (0.0, 1.0)) == pytest.approx(-4.0)
    assert footprint_distance(b, (13.0, 9.0)) == pytest.approx(5.0)
    low = Building.cuboid((50.0, 0.0), (10.0, 10.0, 10.0))
    far = Building.cuboid((900.0, 0.0), (10.0, 10.0, 80.0))
    kos = nearby_keepouts([low, far, b], np.array([30.0, 0.0]), altitude=60.0, reach=100.0, margin=5.0,
                          vertical_clearance=5.0, max_count=4)
    assert len(kos) == 0  # b (30 m) and low are flown over, far is out of reach
    kos = nearby_keepouts([low, far, b], np.array([30.0, 0.0]), altitude=20.0, reach=100.0, margin=5.0,
                          vertical_clearance=5.0, max_count=4)
    assert len(kos) == 1 and np.allclose(kos[0].center, [0.0, 0.0])
