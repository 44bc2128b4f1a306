"""Kinematic closed loops of the papers: teams of unicycle or point-mass UAVs around simulated targets, flying the
onboard guidance, estimation and fusion of :mod:`autonomy` without the physics engine (the paper reproductions,
benchmarks and guidance tests run them)."""
