"""A user's own multi-target tracker, written against the documented protocols only: every radar ground fix of the
latest scan is a track (ids from 1000), and the target is the fix nearest to where the target was last (first: the
cue). Crude, but it shows what the simulator does with a user's tracker that holds many tracks: it is used as it is
(not wrapped), its tracks are recorded and scored, shared with the team, and it receives the cue."""

from __future__ import annotations

import numpy as np

from interfaces.state import TargetEstimate, TrackReport
from tests.simulator.user_modules.centroid import radar_fix


class FixTracks:
    def __init__(self, target_height: float = 0.0) -> None:
        self.target_height = target_height
        self.reports: list[TrackReport] = []
        self._target: int | None = None
        self.last: np.ndarray | None = None
        self.cued = 0

    def cue(self, t, p_W, sigma_m):
        self.cued += 1
        self.last = np.asarray(p_W, dtype=float)[:2]

    def step(self, t, detections):
        fixes = [radar_fix(d, self.target_height) for d in detections if d.kind == "radar"]
        if not fixes:
            return None if self.last is None else TargetEstimate(t=t, p_W=self.last, v_W=np.zeros(2))
        ref = self.last if self.last is not None else fixes[0]
        k = int(np.argmin([np.linalg.norm(f - ref) for f in fixes]))
        P = np.diag([100.0, 100.0, 25.0, 25.0])
        self.reports = [TrackReport(track_id=1000 + j, estimate=TargetEstimate(t=t, p_W=f, v_W=np.zeros(2), P=P),
                                    target_probability=1.0 if j == k else 0.0) for j, f in enumerate(fixes)]
        self._target = 1000 + k
        self.last = fixes[k]
        return self.reports[k].estimate

    def track_reports(self):
        return self.reports

    @property
    def target_track_id(self):
        return self._target
