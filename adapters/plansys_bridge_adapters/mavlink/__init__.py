"""mavlink adapter."""
