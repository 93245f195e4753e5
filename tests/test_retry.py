"""The shared retry policy: fixed waits, a deadline checked before each wait, the
last failure let through, other failures at once."""

from __future__ import annotations

import asyncio
from collections.abc import Sequence

import pytest

from plansys_bridge.retry import retrying


async def attempts(
    policy_kwargs: dict[str, object], outcomes: Sequence[BaseException | None]
) -> int:
    """Run attempts that fail with ``outcomes`` in turn (None: succeed); count them."""
    count = 0
    async for attempt in retrying(**policy_kwargs):  # type: ignore[arg-type]
        with attempt:
            outcome = outcomes[count]
            count += 1
            if outcome is not None:
                raise outcome
    return count


def test_retries_the_named_failure_until_it_works() -> None:
    seen: list[tuple[str, float]] = []
    kwargs = {"every": 0.01, "on": OSError, "before_retry": lambda e, w: seen.append((str(e), w))}
    fails = [OSError("busy"), OSError("still busy"), None]
    assert asyncio.run(attempts(kwargs, fails)) == 3
    assert seen == [("busy", 0.01), ("still busy", 0.01)]


def test_other_failures_pass_at_once() -> None:
    kwargs = {"every": 0.01, "on": (OSError, ValueError)}
    with pytest.raises(KeyError):
        asyncio.run(attempts(kwargs, [OSError("x"), KeyError("y"), None]))


def test_a_test_of_the_error_decides() -> None:
    kwargs = {"every": 0.01, "on": lambda e: "later" in str(e)}
    assert asyncio.run(attempts(kwargs, [RuntimeError("later"), None])) == 2
    with pytest.raises(RuntimeError, match="never"):
        asyncio.run(attempts(kwargs, [RuntimeError("never"), None]))


def test_the_deadline_stops_before_a_wait_that_would_pass_it() -> None:
    # one attempt: waiting 1 s for a second would pass the 0.5 s deadline; the last
    # failure comes at once, not after the wait
    kwargs = {"every": 1.0, "on": OSError, "within": 0.5}
    with pytest.raises(OSError, match="first"):
        asyncio.run(attempts(kwargs, [OSError("first"), OSError("second"), None]))
    kwargs = {"every": 0.01, "on": OSError, "within": 60.0}
    assert asyncio.run(attempts(kwargs, [OSError("a"), OSError("b"), None])) == 3
