"""The lowest layer: typed states and set-points shared by ``autonomy``, ``vehicles`` and ``simulator`` (numpy only)."""
