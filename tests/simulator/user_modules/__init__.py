"""User-style autonomy modules plugged into the simulator by the tests (as a user's own package would be)."""
