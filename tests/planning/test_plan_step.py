"""A plan step's text is written once, when the step is made, and reads as the
joined name and arguments would; equality, hashing, copies and ``replace`` ignore it."""

from __future__ import annotations

import copy
import dataclasses
import pickle

import pytest
from hypothesis import given
from hypothesis import strategies as st

from plansys_bridge.planning.plan import Plan, PlanStep, parse_plan

_NAMES = st.text(alphabet="abcxyz_-0123456789", min_size=1, max_size=8)


@given(
    st.floats(0, 1e6, allow_nan=False),
    _NAMES,
    st.lists(_NAMES, max_size=5).map(tuple),
    st.floats(0, 1e3, allow_nan=False),
)
def test_the_text_kept_is_the_joined_action(
    time: float, action: str, arguments: tuple[str, ...], duration: float
) -> None:
    step = PlanStep(time, action, arguments, duration)
    assert step.text == "(" + " ".join((action, *arguments)) + ")"
    same = PlanStep(time=time, action=action, arguments=arguments, duration=duration)
    assert same == step and hash(same) == hash(step)
    moved = dataclasses.replace(step, action=action + "x")
    assert moved.text == "(" + " ".join((action + "x", *arguments)) + ")"
    assert pickle.loads(pickle.dumps(step)).text == step.text == copy.copy(step).text
    assert repr(step) == (
        f"PlanStep(time={time!r}, action={action!r}, arguments={arguments!r}, "
        f"duration={duration!r})"
    )


def test_the_text_is_frozen_and_not_an_argument() -> None:
    step = parse_plan("0.5: (move r1 a b) [2.0]").steps[0]
    assert step.text == "(move r1 a b)" and step.end == 2.5
    with pytest.raises(dataclasses.FrozenInstanceError):
        step.text = "(other)"  # type: ignore[misc]
    with pytest.raises(ValueError, match="init=False"):
        dataclasses.replace(step, text="(other)")  # type: ignore[call-arg]
    assert [f.name for f in dataclasses.fields(step) if f.compare] == [
        "time",
        "action",
        "arguments",
        "duration",
    ]


@given(
    st.lists(
        st.tuples(st.floats(0, 1e6, allow_nan=False), _NAMES, st.lists(_NAMES, max_size=3)),
        max_size=6,
    )
)
def test_a_plan_message_lists_each_step_as_its_item(
    rows: list[tuple[float, str, list[str]]],
) -> None:
    plan = Plan(tuple(PlanStep(t, a, tuple(args), 1.5) for t, a, args in rows))
    msg = plan.to_msg()
    assert msg.items == tuple(step.to_item() for step in plan.steps)
    assert Plan.from_msg(msg) == Plan(
        tuple(
            PlanStep(s.time, s.action.lower(), tuple(a.lower() for a in s.arguments), 1.5)
            for s in plan.steps
        )
    )
