"""Set-membership search control: sequential distributed one-step MPC over predicted set areas."""
