"""Behaviour-tree actions (PlanSys2's BTAction): an action carried out by a tree
described in BehaviorTree.CPP v4 XML, run on py_trees with node types as plugins.

:mod:`.xml_tree` reads the files, :mod:`.build` maps the control nodes to py_trees,
:mod:`.nodes` holds the node base class, the built-ins and the plugin lookup, and
:mod:`.performer` the ``bt`` performer kind.
"""
