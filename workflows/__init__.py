"""beadrod workflows."""
