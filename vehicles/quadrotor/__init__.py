"""Quadrotor model: airframe parameters, per-rotor physics in PyBullet, cascaded flight controllers and the fleet."""
