"""plansys_bridge.execution."""
