"""Road-constrained target estimation: constant-curvature road approximation, MAEKF / ECUKF, junction hypotheses."""
