"""Reusable FSP model fragments (iterator, sensors, capabilities) for `include`."""
