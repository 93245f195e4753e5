"""The no-headway rule on its own: progress judged on the vehicle's clock."""

from __future__ import annotations

from plansys_bridge_adapters.mavlink.headway import Headway


def test_progress_resets_the_window_and_standing_still_ends_it() -> None:
    h = Headway(window=10)
    assert h.update(100, 0.0)
    assert h.update(90, 5.0)  # 10 m closer: progress at t=5
    assert h.update(89.8, 14.0)  # GPS noise is no progress, but the window holds
    assert h.update(95, 15.0)  # drifting back, 10 s since the progress
    assert not h.update(96, 15.2)
    assert h.best == 90 and h.stalled_for() == 10.2


def test_vehicle_time_not_wall_time_and_a_reboot_starts_again() -> None:
    h = Headway(window=2)
    assert h.update(50, None)  # no vehicle time yet: no judgement
    assert h.update(50, 100.0)
    assert h.update(50, 101.0)
    assert h.update(60, 1.0)  # time went back: the vehicle rebooted
    assert h.update(60, 2.9)
    assert not h.update(60, 3.1)


def test_the_reason_gives_the_vehicles_own_figures() -> None:
    h = Headway(window=2)
    h.update(30, 0.0)
    h.update(41, 3.0)
    text = h.describe("north_field", 41, (-4.0, 3.0, 0.0))
    assert text == (
        "no headway to north_field: 41.0 m away, no closer than 30.0 m for 3 s of vehicle "
        "time, moving at 5.0 m/s over ground; the vehicle reports no fault (wind or a limit "
        "it cannot overcome)"
    )
