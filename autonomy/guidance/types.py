"""Re-exports of the shared states, which live in :mod:`interfaces.state` now."""

from interfaces.state import OwnState, TargetEstimate, TeammateState

__all__ = ["OwnState", "TargetEstimate", "TeammateState"]
