"""beadrod inference."""
