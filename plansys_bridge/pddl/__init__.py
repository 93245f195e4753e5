"""PDDL 2.1 (plus derived predicates and ADL) model, parser and writer."""
