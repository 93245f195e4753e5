"""Node types like PlanSys2's plansys2_bt_example ones, for the BT action tests.

``Move`` takes ``seconds_per_move`` of mission time and checks its ``goal`` port;
``ApproachObject`` is RUNNING for five ticks as upstream's is; the grippers succeed
at once; ``Flaky`` fails its first ``failures`` ticks (a plugin with state, for
RetryUntilSuccessful). A plugin module: the performer's ``plugins:`` names it.
"""

from __future__ import annotations

from py_trees.common import Status

from plansys_bridge.performers.bt.nodes import BtNode

HALTED: list[str] = []
"""Names of nodes halted (cancel), for the tests to see."""


class Move(BtNode):
    ports = frozenset({"goal"})
    required = frozenset({"goal"})

    def initialise(self) -> None:
        self.goal = self.port("goal")
        self.until = self.now() + 2.0

    def tick_node(self) -> Status:
        if self.goal == "nowhere":
            self.feedback_message = "no route to nowhere"
            return Status.FAILURE
        return Status.SUCCESS if self.now() >= self.until else Status.RUNNING

    def halt(self) -> None:
        HALTED.append(f"{self.name} {self.goal}")


class ApproachObject(BtNode):
    ports = frozenset()

    def initialise(self) -> None:
        self.counter = 0

    def tick_node(self) -> Status:
        self.counter += 1
        return Status.RUNNING if self.counter <= 5 else Status.SUCCESS


class OpenGripper(BtNode):
    ports = frozenset()

    def tick_node(self) -> Status:
        return Status.SUCCESS


class CloseGripper(OpenGripper):
    pass


class Flaky(BtNode):
    ports = frozenset({"failures"})
    ticks = 0

    def tick_node(self) -> Status:
        type(self).ticks += 1
        return Status.FAILURE if type(self).ticks <= int(self.port("failures")) else Status.SUCCESS


BT_NODES = {
    "Move": Move,
    "ApproachObject": ApproachObject,
    "OpenGripper": OpenGripper,
    "CloseGripper": CloseGripper,
    "Flaky": Flaky,
}
