"""A user estimator that fails on its first detection: for tests of how runs and campaigns report a crash."""

from __future__ import annotations


class FailingEstimator:
    def step(self, t: float, detections: list) -> None:
        if detections:
            raise RuntimeError("estimator failed on purpose")
        return None
