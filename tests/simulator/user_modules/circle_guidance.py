"""A new guidance mode in one module: fly a fixed circle (world file: ``guidance: {type: circle, params: {radius:
40}}``). Its settings model is checked at load, its builder makes the law, and the last line registers both."""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from autonomy.guidance.base import Guidance
from interfaces.setpoints import VelocitySetpoint
from simulator.builders.guidance import GuidanceContext
from simulator.registry import register_guidance


class CircleSettings(BaseModel):
    """The circle: centre (m), radius (m, > 0) and sense (+1 counter-clockwise)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    centre: tuple[float, float] = (0.0, 0.0)
    radius: float = Field(50.0, gt=0)
    direction: Literal[1, -1] = 1


class FixedCircleGuidance(Guidance):
    """Velocity set-points along the circle at ``speed`` (m/s), pulled onto it radially, holding ``altitude`` (m)."""

    def __init__(self, settings: CircleSettings, speed: float, altitude: float) -> None:
        super().__init__()
        self.settings, self.speed, self.altitude = settings, speed, altitude

    def command(self, own, target, teammates, t):
        self.stats.calls += 1
        r = own.p_W[:2] - np.asarray(self.settings.centre)
        d = float(np.hypot(*r)) + 1e-9
        tangent = self.settings.direction * np.array([-r[1], r[0]]) / d
        v = self.speed * tangent - 0.3 * (d - self.settings.radius) * r / d
        return VelocitySetpoint(v_W=np.array([v[0], v[1], 0.8 * (self.altitude - own.p_W[2])]), yaw=None)


def build_circle(ctx: GuidanceContext) -> FixedCircleGuidance:
    g = ctx.uav.autonomy.guidance
    return FixedCircleGuidance(g.settings, speed=g.speed, altitude=g.altitude)


register_guidance("circle", CircleSettings, build_circle)
