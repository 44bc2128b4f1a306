"""Off-screen video of recorded runs: replayed PyBullet scenes, cameras, overlays of what the autonomy believes."""
