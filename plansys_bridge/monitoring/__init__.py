"""plansys_bridge.monitoring."""
