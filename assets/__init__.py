"""Data files the scene loads: URDFs, meshes, map extracts (with their licences)."""
