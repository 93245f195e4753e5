"""plansys_bridge.planning."""
