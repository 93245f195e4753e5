"""The router keeps the performers a REQUEST's arguments pick (a plan asks for the same
ground actions again and again); what it hands a REQUEST from what it kept must be
what PlanSys2's rule picks among the subscribers of that moment, while performers
come and go between REQUESTs and plain subscribers share the action."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from plansys_bridge.hub.messages import ExecutionType, Topics, action_execution
from plansys_bridge.hub.routing import TopicRouter, arguments_match, client_keys, performer_keys
from plansys_bridge.hub.transport import Subscription

VALUES = st.sampled_from(["", "r1", "r2"])
SPECS = st.lists(VALUES, max_size=2).map(tuple)
ARGS = st.lists(st.sampled_from(["r1", "r2"]), max_size=2).map(tuple)
STEPS = st.lists(
    st.one_of(
        st.tuples(st.just("add"), SPECS),
        st.tuples(st.just("close"), st.integers(0, 5)),
        st.tuples(st.just("request"), ARGS),
        st.tuples(st.just("request as list"), ARGS),
    ),
    max_size=14,
)


@settings(max_examples=300, deadline=None)
@given(steps=STEPS)
def test_kept_candidates_are_what_the_rule_picks_now(
    steps: list[tuple[str, object]],
) -> None:
    router = TopicRouter(Topics.ACTIONS_HUB)
    heard: list[int] = []
    live: dict[int, tuple[tuple[str, ...], Subscription]] = {}
    added = 0
    for kind, value in steps:
        if kind == "add":
            assert isinstance(value, tuple)
            sub = router.add(
                lambda m, i=added: heard.append(i),
                performer_keys(f"n{added}", {"move": value}),
            )
            live[added] = (value, sub)
            added += 1
        elif kind == "close":
            assert isinstance(value, int)
            if value in live:
                live.pop(value)[1].close()
        else:
            assert isinstance(value, tuple)
            arguments = list(value) if kind == "request as list" else value
            msg = action_execution(ExecutionType.REQUEST, "", "move", arguments)  # type: ignore[arg-type]
            heard.clear()
            router.dispatch(msg)
            expected = [i for i, (spec, _) in live.items() if arguments_match(spec, value)]
            assert heard == expected
            assert router.wants(msg) == bool(expected)


def test_a_kept_answer_is_forgotten_when_the_performers_change() -> None:
    router = TopicRouter(Topics.ACTIONS_HUB)
    heard: list[str] = []
    first = router.add(lambda m: heard.append("a"), performer_keys("a", {"move": ("r1",)}))
    msg = action_execution(ExecutionType.REQUEST, "", "move", ("r1", "x"))
    router.dispatch(msg)
    router.add(lambda m: heard.append("b"), performer_keys("b", {"move": ("r1",)}))
    router.dispatch(msg)
    first.close()
    router.dispatch(msg)
    assert heard == ["a", "a", "b", "b"]


@settings(max_examples=100, deadline=None)
@given(
    keys=st.lists(st.sampled_from(["q1", "q2"]), min_size=1, max_size=4),
    order=st.permutations(range(4)),
)
def test_leaving_a_route_alone_or_shared_leaves_the_others(
    keys: list[str], order: list[int]
) -> None:
    router = TopicRouter(Topics.ACTIONS_HUB)
    heard: list[int] = []
    subs = {
        i: router.add(lambda m, i=i: heard.append(i), client_keys(rid, "move", ("r1",)))
        for i, rid in enumerate(keys)
    }
    for i in order:
        if i not in subs:
            continue
        subs.pop(i).close()
        for rid in ("q1", "q2"):
            heard.clear()
            router.dispatch(
                action_execution(ExecutionType.FINISH, "p", "move", ("r1",), request_id=rid)
            )
            assert heard == [j for j in sorted(subs) if keys[j] == rid]
    assert len(router) == 0
