"""Formation guidance for bearings-only tracking: det(FIM)-optimal sensor geometry (Yang & Wang 2019, Algorithm 1)
and a PD controller in Jacobi coordinates that drives the agents there."""
