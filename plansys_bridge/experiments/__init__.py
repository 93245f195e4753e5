"""Experiments that reproduce and extend the PlanSys2 paper's measurements."""
