"""An independent PlanSys2 action performer on Cyclone DDS, written for the tests.

Nothing here comes from the project: the DDS types are typed from upstream's
``plansys2_msgs`` texts (quoted below) and the behaviour follows PlanSys2's
``plansys2_executor/src/plansys2_executor/ActionExecutorClient.cpp`` (2.0.12) and
the simple example's ``MoveAction``:

* configured: heartbeat ``ActionPerformerStatus`` on ``performers_status`` every 1 s
  (READY while inactive, RUNNING while active), QoS(100).reliable();
* ``actions_hub`` QoS(100).reliable(): on REQUEST, when inactive, not committed and
  ``should_execute`` (action name equal, specialised arguments equal position by
  position, empty string matching anything) -> committed, RESPONSE (a copy of the
  request with type RESPONSE and our node id);
* CONFIRM for us while inactive and committed -> activate with the request's
  arguments, uncommitted; REJECT for us -> uncommitted; CANCEL for us while active ->
  deactivate (no FINISH);
* active: ``do_work`` at ``rate`` Hz: progress += 1/steps, FEEDBACK while below 1,
  then deactivate and FINISH(success, 1.0, status).

No ``from __future__ import annotations``: cyclonedds reads the field annotations.
"""

import threading
import time
from dataclasses import dataclass, field

from cyclonedds.core import Policy, Qos, ReadCondition, SampleState, WaitSet
from cyclonedds.domain import Domain, DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float32, int8, int16, int32, sequence, uint32
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

# builtin_interfaces/msg/Time.msg:
#   int32 sec
#   uint32 nanosec


@dataclass
class Time_(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32 = 0
    nanosec: uint32 = 0


# plansys2_msgs/msg/ActionExecution.msg:
#   int16 REQUEST=1 ... int16 CANCEL=7
#   int16 type / string node_id / string action / string[] arguments /
#   bool success / float32 completion / string status
REQUEST, RESPONSE, CONFIRM, REJECT, FEEDBACK, FINISH, CANCEL = range(1, 8)


@dataclass
class ActionExecution_(IdlStruct, typename="plansys2_msgs::msg::dds_::ActionExecution_"):
    type: int16 = 0
    node_id: str = ""
    action: str = ""
    arguments: sequence[str] = field(default_factory=list)
    success: bool = False
    completion: float32 = 0.0
    status: str = ""


# plansys2_msgs/msg/ActionPerformerStatus.msg:
#   int8 NOT_READY=0 / int8 READY=1 / int8 RUNNING=2 / int8 FAILURE=4
#   builtin_interfaces/Time status_stamp / int8 state / string action /
#   string[] specialized_arguments / string node_name
NOT_READY, READY, RUNNING, FAILURE = 0, 1, 2, 4


@dataclass
class ActionPerformerStatus_(
    IdlStruct, typename="plansys2_msgs::msg::dds_::ActionPerformerStatus_"
):
    status_stamp: Time_ = field(default_factory=Time_)
    state: int8 = 0
    action: str = ""
    specialized_arguments: sequence[str] = field(default_factory=list)
    node_name: str = ""


# plansys2_msgs/msg/PlanItem.msg: float32 time / string action / float32 duration
@dataclass
class PlanItem_(IdlStruct, typename="plansys2_msgs::msg::dds_::PlanItem_"):
    time: float32 = 0.0
    action: str = ""
    duration: float32 = 0.0


# plansys2_msgs/msg/Plan.msg: plansys2_msgs/PlanItem[] items
@dataclass
class Plan_(IdlStruct, typename="plansys2_msgs::msg::dds_::Plan_"):
    items: sequence[PlanItem_] = field(default_factory=list)


# plansys2_msgs/msg/Knowledge.msg:
#   string[] instances / string[] predicates / string[] functions / string goal
@dataclass
class Knowledge_(IdlStruct, typename="plansys2_msgs::msg::dds_::Knowledge_"):
    instances: sequence[str] = field(default_factory=list)
    predicates: sequence[str] = field(default_factory=list)
    functions: sequence[str] = field(default_factory=list)
    goal: str = ""


def loopback_domain(domain_id: int) -> Domain:
    """Cyclone on 127.0.0.1 only, unicast discovery by participant index (as the tests use)."""
    xml = (
        '<CycloneDDS xmlns="https://cdds.io/config">'
        f'<Domain Id="{domain_id}"><General>'
        '<Interfaces><NetworkInterface address="127.0.0.1" multicast="false"/></Interfaces>'
        "<AllowMulticast>false</AllowMulticast></General>"
        "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
        "<MaxAutoParticipantIndex>19</MaxAutoParticipantIndex>"
        '<Peers><Peer address="127.0.0.1"/></Peers></Discovery>'
        "</Domain></CycloneDDS>"
    )
    return Domain(domain_id, xml)


def _qos() -> Qos:
    # rclcpp::QoS(100).reliable(): keep last 100, reliable, volatile; XCDR1 as rmw_cyclonedds.
    return Qos(
        Policy.Reliability.Reliable(duration(seconds=1)),
        Policy.History.KeepLast(100),
        Policy.Durability.Volatile,
        Policy.DataRepresentation(use_cdrv0_representation=True),
    )


class PlanSys2Performer:
    """One ``ActionExecutorClient`` node, run by a thread of its own."""

    def __init__(
        self,
        domain_id: int,
        node_name: str,
        action: str,
        specialized_arguments: tuple[str, ...] = (),
        *,
        rate: float = 10.0,
        steps: int = 4,
        success: bool = True,
    ) -> None:
        self.domain_id = domain_id
        self.node_name = node_name
        self.action_managed = action
        self.specialized_arguments = list(specialized_arguments)
        self.period = 1.0 / rate
        self.steps = steps
        self.success = success
        self.active = False
        self.committed = False
        self.current_arguments: list[str] = []
        self.progress = 0.0
        self.confirmed: list[tuple[str, ...]] = []
        """Arguments of every CONFIRM this node acted on."""
        self.finished: list[tuple[str, ...]] = []
        self.cancelled: list[tuple[str, ...]] = []
        self.rejects = 0
        self.responses = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name=f"peer-{node_name}", daemon=True)
        self._lock = threading.Lock()

    # -- lifecycle ---------------------------------------------------------------------
    def start(self) -> None:
        p = DomainParticipant(self.domain_id)
        self._participant = p
        hub = Topic(p, "rt/actions_hub", ActionExecution_)
        status = Topic(p, "rt/performers_status", ActionPerformerStatus_)
        self._hub_writer = DataWriter(p, hub, _qos())
        self._status_writer = DataWriter(p, status, _qos())
        self._hub_reader = DataReader(p, hub, _qos())
        self._waitset = WaitSet(p)
        self._waitset.attach(ReadCondition(self._hub_reader, SampleState.NotRead))
        self._thread.start()

    def matched_writers(self) -> int:
        """How many ``actions_hub`` writers this node's reader has matched (own included)."""
        return int(self._hub_reader.get_subscription_matched_status().current_count)

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)
        self._participant.__del__()  # leave the domain now, not at garbage collection

    def _run(self) -> None:
        next_beat = time.monotonic()
        next_work = next_beat
        while not self._stop.is_set():
            self._waitset.wait(duration(milliseconds=20))
            for sample in self._hub_reader.take(N=100):
                if sample.sample_info.valid_data:
                    self._on_hub(sample)
            now = time.monotonic()
            if now >= next_beat:
                next_beat = now + 1.0
                self._heartbeat()
            if self.active and now >= next_work:
                next_work = now + self.period
                self._do_work()
            elif not self.active:
                next_work = now + self.period

    # -- ActionExecutorClient ----------------------------------------------------------
    def _heartbeat(self) -> None:
        sec, frac = divmod(time.time(), 1.0)
        self._status_writer.write(
            ActionPerformerStatus_(
                status_stamp=Time_(int(sec), int(frac * 1e9)),
                state=RUNNING if self.active else READY,
                action=self.action_managed,
                specialized_arguments=list(self.specialized_arguments),
                node_name=self.node_name,
            )
        )

    def _on_hub(self, msg: ActionExecution_) -> None:
        if msg.type == REQUEST:
            if not self.active and not self.committed and self._should_execute(msg):
                self.committed = True
                self.responses += 1
                self._hub_writer.write(
                    ActionExecution_(
                        type=RESPONSE,
                        node_id=self.node_name,
                        action=msg.action,
                        arguments=list(msg.arguments),
                        success=msg.success,
                        completion=msg.completion,
                        status=msg.status,
                    )
                )
        elif msg.type == CONFIRM:
            if not self.active and self.committed and msg.node_id == self.node_name:
                self.current_arguments = list(msg.arguments)
                self.confirmed.append(tuple(msg.arguments))
                self.active = True  # on_activate
                self.progress = 0.0
                self._heartbeat()
                self.committed = False
        elif msg.type == REJECT:
            if msg.node_id == self.node_name:
                self.rejects += 1
                self.committed = False
        elif msg.type == CANCEL and self.active and msg.node_id == self.node_name:
            self.active = False  # on_deactivate
            self.cancelled.append(tuple(self.current_arguments))

    def _should_execute(self, msg: ActionExecution_) -> bool:
        if msg.action != self.action_managed:
            return False
        for want, have in zip(self.specialized_arguments, msg.arguments, strict=False):
            if want != "" and have != "" and want != have:
                return False
        return True

    def _do_work(self) -> None:
        self.progress += 1.0 / self.steps
        if self.progress < 1.0:
            self._send(FEEDBACK, self.progress, "moving")
            return
        self.active = False  # finish(): deactivate, then FINISH
        self.finished.append(tuple(self.current_arguments))
        self._send(FINISH, 1.0, "done" if self.success else "blocked", success=self.success)

    def _send(self, kind: int, completion: float, status: str, *, success: bool = False) -> None:
        self._hub_writer.write(
            ActionExecution_(
                type=kind,
                node_id=self.node_name,
                action=self.action_managed,
                arguments=list(self.current_arguments),
                success=success,
                completion=completion,
                status=status,
            )
        )
