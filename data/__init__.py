"""beadrod data."""
