"""Airframe parameter files, one module per airframe, each exposing ``PARAMS``."""
