"""One retry policy for the adapters' retry loops, on tenacity.

Opening a MAVLink link, arming a vehicle that is still starting up and reopening a
CAN interface after a driver error all do the same thing: try, and on a failure
that waiting may cure, wait a fixed period and try again, until a deadline (or for
ever), then let the last failure through. :func:`retrying` says that once::

    async for attempt in retrying(every=0.5, within=30.0, on=OSError):
        with attempt:
            conn = await open_link()

The deadline is checked before each wait (tenacity's ``stop_before_delay``): no
attempt starts after ``within`` seconds, and the failure comes as soon as another
wait could not fit, not a period late.
"""

from __future__ import annotations

from collections.abc import Callable

from tenacity import (
    AsyncRetrying,
    RetryCallState,
    retry_if_exception,
    stop_before_delay,
    stop_never,
    wait_fixed,
)

RetryOn = type[BaseException] | tuple[type[BaseException], ...] | Callable[[BaseException], bool]
"""The failures worth another attempt: exception types, or a test of the exception."""


def retrying(
    *,
    every: float,
    on: RetryOn,
    within: float | None = None,
    before_retry: Callable[[BaseException, float], None] | None = None,
) -> AsyncRetrying:
    """Attempts ``every`` seconds apart while they fail with ``on``, for at most
    ``within`` seconds (None: until the task is cancelled); the last failure, or one
    not in ``on``, is raised as it is. ``before_retry(error, every)`` runs before
    each wait (to log it)."""
    if isinstance(on, type | tuple):
        kinds = on
        worth: Callable[[BaseException], bool] = lambda exc: isinstance(exc, kinds)  # noqa: E731
    else:
        worth = on

    def before_sleep(state: RetryCallState) -> None:
        error = state.outcome.exception() if state.outcome is not None else None
        if before_retry is not None and error is not None:
            before_retry(error, every)

    return AsyncRetrying(
        wait=wait_fixed(every),
        stop=stop_never if within is None else stop_before_delay(max(0.0, within)),
        retry=retry_if_exception(worth),
        before_sleep=before_sleep,
        reraise=True,
    )
