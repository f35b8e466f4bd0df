"""Measurements: read solver state on its device, return numbers to the host."""
