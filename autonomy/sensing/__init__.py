"""sensing package."""
