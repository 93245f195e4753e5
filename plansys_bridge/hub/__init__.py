"""plansys_bridge.hub."""
