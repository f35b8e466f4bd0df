"""Scene description: geometry to particles, and the built-in cases."""
