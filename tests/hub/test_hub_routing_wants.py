"""``TopicRouter.wants`` answers an auction's RESPONSEs and REJECTs with the look-ups
dispatch places them by: whatever the router holds (performers, keyed client
subscriptions, clients of the hub's table, plain subscribers), it must want exactly
the messages dispatch would hand to somebody."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.hub.messages import ExecutionType, Topics, action_execution
from plansys_bridge.hub.routing import TopicRouter, client_keys, performer_keys
from plansys_bridge.hub.transport import Subscription

NODES = st.sampled_from(["p1", "p2", "p3"])
RIDS = st.sampled_from(["", "q1", "q2"])
ACTIONS = st.sampled_from(["move", "pick"])
ARGS = st.sampled_from([("r1",), ("r2",), ("r1", "a")])


class _Client:
    """What the table needs of a client (``TableClient``), telling ``heard``."""

    def __init__(self, request_id: str, action: str, arguments: tuple[str, ...], heard: list[str]):
        self.request_id, self.action, self.arguments = request_id, action, arguments
        self.order = 0
        self.closed = False
        self.heard = heard

    def callback(self, msg: object) -> None:
        self.heard.append(self.request_id)


STEPS = st.lists(
    st.one_of(
        st.tuples(st.just("performer"), NODES, ACTIONS, st.sampled_from(["", "r1"])),
        st.tuples(st.just("keyed client"), RIDS, ACTIONS, ARGS),
        st.tuples(st.just("table client"), RIDS, ACTIONS, ARGS),
        st.tuples(st.just("everyone"), NODES, ACTIONS, ARGS),
        st.tuples(st.just("close"), st.integers(0, 7), ACTIONS, ARGS),
        st.tuples(st.just("leave"), st.integers(0, 7), ACTIONS, ARGS),
    ),
    max_size=10,
)
MESSAGES = st.lists(
    st.tuples(st.sampled_from(list(ExecutionType)), NODES, RIDS, ACTIONS, ARGS),
    min_size=1,
    max_size=8,
)


@settings(max_examples=300, deadline=None)
@given(steps=STEPS, messages=MESSAGES)
def test_the_router_wants_what_dispatch_delivers(
    steps: list[tuple[str, object, str, tuple[str, ...]]],
    messages: list[tuple[ExecutionType, str, str, str, tuple[str, ...]]],
) -> None:
    router = TopicRouter(Topics.ACTIONS_HUB)
    heard: list[object] = []
    subs: list[Subscription] = []
    clients: list[_Client] = []
    for kind, value, action, arguments in steps:
        if kind == "performer":
            assert isinstance(value, str)
            keys = performer_keys(value, {action: [arguments] if arguments else []})
            subs.append(router.add(heard.append, keys))
        elif kind == "keyed client":
            assert isinstance(value, str)
            subs.append(router.add(heard.append, client_keys(value, action, arguments)))
        elif kind == "table client":
            assert isinstance(value, str)
            client = _Client(value, action, arguments, heard)  # type: ignore[arg-type]
            router.clients.join(client)
            clients.append(client)
        elif kind == "everyone":
            subs.append(router.add(heard.append, None))
        elif kind == "close" and subs:
            assert isinstance(value, int)
            subs[value % len(subs)].close()
        elif kind == "leave" and clients:
            assert isinstance(value, int)
            left = clients[value % len(clients)]
            if not left.closed:
                router.clients.leave(left)  # type: ignore[arg-type]
    for kind, node, rid, action, arguments in messages:
        msg = action_execution(kind, node, action, arguments, request_id=rid)
        wanted = router.wants(msg)
        heard.clear()
        router.dispatch(msg)
        assert wanted == bool(heard), (msg, heard)


def test_a_reject_is_wanted_only_where_its_node_listens() -> None:
    router = TopicRouter(Topics.ACTIONS_HUB)
    reject = action_execution(ExecutionType.REJECT, "p1", "move", ("r1",), request_id="q1")
    response = action_execution(ExecutionType.RESPONSE, "p1", "move", ("r1",), request_id="q1")
    assert not router.wants(reject) and not router.wants(response)
    sub = router.add(lambda m: None, performer_keys("p1", ["move"]))
    assert router.wants(reject) and not router.wants(response)
    client = _Client("q1", "move", ("r1",), [])
    router.clients.join(client)  # type: ignore[arg-type]
    assert router.wants(response)
    router.clients.leave(client)  # type: ignore[arg-type]
    sub.close()
    assert not router.wants(reject) and not router.wants(response)
