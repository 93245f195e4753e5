"""Test support for adapter packages: the performer contract suite.

``from plansys_bridge.testing import PerformerContract`` and subclass it in a test
module; pytest then runs every contract test against your performer on the
in-process hub (see :mod:`plansys_bridge.testing.contract`).
"""

from plansys_bridge.testing.contract import PerformerContract

__all__ = ["PerformerContract"]
