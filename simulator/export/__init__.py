"""Exporting a recorded run directory to the formats of outside viewers: Rerun (``.rrd``) and MCAP (Foxglove)."""
