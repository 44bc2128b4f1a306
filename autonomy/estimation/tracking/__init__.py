"""Tracking composed of small parts in Stone Soup's manner: a :class:`~.track.Track` per target hypothesis, an
initiator, a χ² gate and an associator, deleters, and the filter each track runs; :class:`~.tracker.Tracker` wires
them. :class:`autonomy.estimation.tracker.SingleTargetTracker` is its configured single-target form."""
