"""Builders of the autonomy components a world file names: one function per sensor, estimator and guidance tag, looked
up in :mod:`simulator.registry`."""
