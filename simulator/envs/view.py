"""Off-screen frames of a running episode, drawn by the replay renderer (:mod:`simulator.render`).

The renderer's :class:`~simulator.render.stage.Stage` holds the episode's buildings and roads in a PyBullet client of
its own (the physics client is never drawn from), and its UAV and car bodies are posed from the episode's state at
each frame, as a replay poses them from the record. Two uses:

- ``render()``: a chase view behind the learning UAV looking at the true target, or the whole area from above, for
  people watching;
- the observation's camera image: the UAV's onboard view with the gimbal on the learner's target *estimate* (the
  scene it shows is what a camera there would see).

The software renderer (TinyRenderer) draws both: it runs everywhere and costs little at these sizes.
"""

from __future__ import annotations

import numpy as np

from simulator.envs.episode import Episode
from simulator.render.cameras import CameraInputs, CameraRig, ChaseCamera, OnboardCamera, TopDownCamera
from simulator.render.config import RenderConfig
from simulator.render.stage import StaticGeometry, Stage
from simulator.render.world_view import ReplayWorld
from worlds.schema import World

__all__ = ["LiveView"]

_STYLE = RenderConfig()
"""Camera placements and sizes of the replay videos, reused so that a frame here looks like a frame there."""
_ROAD_STEP_M = 5.0  # spacing of the road centre-line points drawn (m), as in the run's geometry.npz
_TOPDOWN_VFOV = np.deg2rad(40.0)


def _roads(episode: Episode) -> list[np.ndarray]:
    net = episode.geometry.network
    if net is None:
        return []
    return [np.asarray(r.point(np.linspace(0.0, r.length, max(2, int(r.length / _ROAD_STEP_M) + 1))))
            for r in net.roads.values()]


class LiveView:
    """Renders frames of ``episode`` (of the world ``world``)."""

    def __init__(self, episode: Episode, world: World) -> None:
        self.episode = episode
        rw = ReplayWorld(world)
        self.geometry = StaticGeometry(list(episode.geometry.buildings), _roads(episode))
        n_uavs, n_cars = len(world.uavs), len(world.ground_vehicles)
        self.uav_span = 2.0 * rw.uav_arm_length() * _STYLE.uav_scale
        self.stage = Stage(self.geometry, n_uavs, [rw.vehicle_size(v) for v in range(n_cars)], self.uav_span,
                           use_egl=False, decoys=rw.decoys())
        self._rigs: dict[tuple[str, int], CameraRig] = {}

    def _rig(self, camera: str, aspect: float) -> CameraRig:
        key = (camera, int(round(1000 * aspect)))
        if key not in self._rigs:  # tau 0: an environment's frames are far apart, a smoothed camera would lag
            if camera == "chase":
                rig: CameraRig = ChaseCamera(_STYLE.chase_vfov, 0.0, _STYLE.chase_back_m, _STYLE.chase_up_m)
            elif camera == "onboard":
                rig = OnboardCamera(_STYLE.vfov, 0.0, _STYLE.onboard_pitch, 0.75 * self.uav_span, True)
            else:
                rig = TopDownCamera(_TOPDOWN_VFOV, 0.0, aspect, self.geometry.bounds(), _STYLE.topdown_span_m)
            self._rigs[key] = rig
        return self._rigs[key]

    def _pose(self) -> None:
        asm = self.episode.assembly
        st = asm.quads.state
        uavs = [(st.p_W[i], st.q_WB[i]) for i in range(len(st.p_W))]
        cars = []
        if asm.cars is not None:
            cs = asm.cars.state
            yaw = np.asarray(cs.yaw, dtype=float)
            cars = [(cs.p_W[k], np.array([0.0, 0.0, np.sin(yaw[k] / 2), np.cos(yaw[k] / 2)])) for k in range(len(yaw))]
        self.stage.set_poses(uavs, cars)

    def frame(self, camera: str, uav: int, look_at_W: np.ndarray, size: tuple[int, int]) -> np.ndarray:
        """(H, W, 3) uint8 image of ``camera`` (``chase``, ``topdown`` or ``onboard``) for UAV ``uav`` looking at
        ``look_at_W`` (3,) m, ``size`` = (height, width) px."""
        h, w = int(size[0]), int(size[1])
        self._pose()
        st = self.episode.assembly.quads.state
        inputs = CameraInputs(t=self.episode.t, p_uav_W=np.array(st.p_W[uav], dtype=float), q_uav_WB=st.q_WB[uav],
                              p_target_W=np.asarray(look_at_W, dtype=float).copy())
        view = self._rig(camera, w / h).view(inputs, 0.0)
        rgb, _ = self.stage.render(view, w, h)
        return rgb

    def close(self) -> None:
        """Disconnect the stage's PyBullet client (idempotent)."""
        if self.stage is not None:
            self.stage.close()
            self.stage = None
