"""A hub with a fleet key: unsigned, forged and replayed messages change nothing.

"mallory" is a process on the same bus that sees all traffic (signed messages are
readable, not secret) and answers every REQUEST first: plain and unsigned like a stock
PlanSys2 performer, or signed with a key of its own. The control runs the same
scenario without a key, where mallory wins, so the tests can fail.
"""

from __future__ import annotations

import asyncio
import json
import logging
from dataclasses import replace
from typing import Any

import pytest

from plansys_bridge.clock import VirtualClock, run
from plansys_bridge.hub.auction import ActionClient, ActionOutcome
from plansys_bridge.hub.auth import SIGNED_TOPIC, AuthTransport, SignedMessage, Signer, load_key
from plansys_bridge.hub.hub import Hub
from plansys_bridge.hub.messages import (
    ActionExecution,
    ActionPerformerStatus,
    ExecutionType,
    PerformerState,
    Topics,
)
from plansys_bridge.hub.transport import InProcessTransport
from plansys_bridge.performers.base import PerformerContext
from plansys_bridge.performers.simulated import SimulatedPerformer

KEY = b"fleet-key-0123456789abcdef"


class Mallory:
    """Answers every REQUEST at once, FINISHes when confirmed, CANCELs others' actions."""

    def __init__(self, bus: InProcessTransport, mode: str) -> None:
        self.bus, self.mode = bus, mode
        self.forger = Signer(b"not-the-fleet-key-at-all")
        self.captured: list[SignedMessage] = []
        bus.subscribe(Topics.ACTIONS_HUB, self.on_msg)
        bus.subscribe(SIGNED_TOPIC, self.on_signed)

    def on_signed(self, signed: object) -> None:
        assert isinstance(signed, SignedMessage)
        self.captured.append(signed)
        if signed.topic == Topics.ACTIONS_HUB:
            data = json.loads(signed.payload)
            self.on_msg(
                ActionExecution(
                    **{
                        **data,
                        "type": ExecutionType(data["type"]),
                        "arguments": tuple(data["arguments"]),
                    }
                )
            )

    def send(self, msg: ActionExecution) -> None:
        if self.mode == "forged":
            self.bus.publish(SIGNED_TOPIC, self.forger.sign(Topics.ACTIONS_HUB, msg))
        else:
            self.bus.publish(Topics.ACTIONS_HUB, msg)

    def on_msg(self, msg: object) -> None:
        if not isinstance(msg, ActionExecution) or (
            msg.node_id == "mallory"
            and msg.type
            in (
                ExecutionType.RESPONSE,
                ExecutionType.FINISH,
            )
        ):
            return
        if msg.type is ExecutionType.REQUEST:
            self.send(replace(msg, type=ExecutionType.RESPONSE, node_id="mallory"))
        elif msg.type is ExecutionType.CONFIRM and msg.node_id == "mallory":
            self.send(replace(msg, type=ExecutionType.FINISH, success=True, status="mallory"))
        elif msg.type is ExecutionType.CONFIRM:
            self.send(replace(msg, type=ExecutionType.CANCEL))


def auction(mode: str, *, signed: bool) -> tuple[ActionOutcome, int]:
    clock = VirtualClock()
    bus = InProcessTransport()
    Mallory(bus, mode)  # subscribed first: its answers go out first
    transport = AuthTransport(bus, KEY) if signed else bus
    hub = Hub(transport, clock)
    good = SimulatedPerformer(
        PerformerContext(hub, clock), "good", {"move": []}, default_duration=3.0
    )

    async def main() -> ActionOutcome:
        await hub.start()
        await good.start()
        try:
            return await ActionClient(hub, "move", ["r1"], request_id="p:0").run()
        finally:
            await good.stop()
            await hub.close()

    outcome = run(main(), clock)
    return outcome, getattr(transport, "refused", 0)


@pytest.mark.parametrize("mode", ["plain", "forged"])
def test_without_a_key_mallory_wins_or_cancels(mode: str) -> None:
    outcome, _ = auction(mode, signed=False)
    if mode == "plain":
        assert outcome.performer == "mallory" and outcome.status == "mallory"
    else:  # without a key nobody reads signed messages: mallory is simply not heard
        assert outcome.performer == "good"


@pytest.mark.parametrize("mode", ["plain", "forged"])
def test_with_a_key_only_the_signed_performer_wins_finishes_and_is_cancelled(mode: str) -> None:
    outcome, refused = auction(mode, signed=True)
    assert outcome.success and outcome.performer == "good"
    assert outcome.status == "(move r1) done in 3 s"  # not mallory's FINISH, not cancelled
    assert refused >= 2  # the RESPONSE and the CANCEL at least


def test_a_replayed_finish_is_refused() -> None:
    clock = VirtualClock()
    bus = InProcessTransport()
    captured: list[SignedMessage] = []
    bus.subscribe(SIGNED_TOPIC, lambda m: captured.append(m))  # type: ignore[arg-type]
    transport = AuthTransport(bus, KEY)
    hub = Hub(transport, clock)
    good = SimulatedPerformer(
        PerformerContext(hub, clock),
        "good",
        {"move": []},
        durations={"(move r1)": 1.0},
        default_duration=10.0,
    )

    def finishes() -> list[SignedMessage]:
        return [s for s in captured if '"type":6' in s.payload]

    async def main() -> tuple[ActionOutcome, float]:
        await hub.start()
        await good.start()
        try:
            first = await ActionClient(hub, "move", ["r1"], request_id="p:0").run()
            assert first.success and len(finishes()) == 1
            # The same request id again (a retried plan): the old FINISH must not end it.
            client = ActionClient(hub, "move", ["r2"], request_id="p:0")
            task = asyncio.ensure_future(client.run())
            await asyncio.sleep(0.5)
            bus.publish(SIGNED_TOPIC, finishes()[0])
            t0 = clock.now()
            outcome = await task
            return outcome, clock.now() - t0
        finally:
            await good.stop()
            await hub.close()

    outcome, waited = run(main(), clock)
    assert outcome.success and outcome.status == "(move r2) done in 10 s"
    assert waited == pytest.approx(9.5)
    assert transport.refused == 1


def test_unsigned_heartbeats_are_refused_with_one_log_line_per_performer(
    caplog: pytest.LogCaptureFixture,
) -> None:
    clock = VirtualClock()
    bus = InProcessTransport()
    transport = AuthTransport(bus, KEY)
    hub = Hub(transport, clock)
    seen: list[object] = []

    async def main() -> None:
        await hub.start()
        hub.subscribe(Topics.PERFORMERS_STATUS, seen.append)
        for _ in range(3):
            for name in ("plansys2_a", "plansys2_b"):
                status = ActionPerformerStatus(clock.now(), PerformerState.READY, "move", (), name)
                bus.publish(Topics.PERFORMERS_STATUS, status)
            await asyncio.sleep(1.0)
        await hub.close()

    with caplog.at_level(logging.WARNING, logger="plansys_bridge.hub.auth"):
        run(main(), clock)
    assert seen == []
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 2
    assert all("unsigned" in line for line in lines)
    assert transport.refused == 6


def test_key_file_errors_name_the_key(tmp_path: Any) -> None:
    from plansys_bridge.errors import ConfigError

    short = tmp_path / "short.key"
    short.write_text("abc\n")
    with pytest.raises(ConfigError, match="at least 16") as err:
        load_key(short)
    assert err.value.key == "auth.key_file"
    with pytest.raises(ConfigError, match="cannot read"):
        load_key(tmp_path / "missing.key")
    good = tmp_path / "fleet.key"
    good.write_text(KEY.decode() + "\n")
    assert load_key(good) == KEY


@pytest.mark.timeout(60)
def test_over_dds_signed_messages_pass_and_unsigned_ones_do_not() -> None:
    pytest.importorskip("cyclonedds", reason="cyclonedds (extra 'dds') is not installed")
    import random

    from plansys_bridge.hub.dds import DdsTransport

    async def main() -> list[str]:
        domain = random.SystemRandom().randint(1, 232)
        sender = AuthTransport(DdsTransport(domain), KEY)
        receiver = AuthTransport(DdsTransport(domain), KEY)
        stranger = DdsTransport(domain)
        got: list[str] = []
        try:
            for t in (sender, receiver, stranger):
                await t.start()
            await sender.wait_for_peers(2, topic=SIGNED_TOPIC, timeout=10)
            await stranger.wait_for_peers(2, timeout=10)
            receiver.subscribe(Topics.ACTIONS_HUB, lambda m: got.append(m.node_id))  # type: ignore[attr-defined]
            move = ActionExecution(ExecutionType.RESPONSE, "", "move", ("r1",), request_id="p:0")
            stranger.publish(Topics.ACTIONS_HUB, replace(move, node_id="stranger"))
            sender.publish(Topics.ACTIONS_HUB, replace(move, node_id="fleet"))
            async with asyncio.timeout(10):
                while "fleet" not in got:
                    await asyncio.sleep(0.01)
            await asyncio.sleep(0.3)
            assert receiver.refused >= 1
        finally:
            for t in (stranger, receiver, sender):
                await t.close()
        return got

    assert asyncio.run(main()) == ["fleet"]
