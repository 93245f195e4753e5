"""How the simulated vehicle moves: GUIDED targets, take-off, LAND and RTL.

A copter climbs, flies straight to its target at cruise speed and descends at
ArduCopter's LAND speeds (faster above 10 m); a rover drives straight. RTL climbs to
``rtl_alt``, returns home and lands (copter) or drives home (rover).
"""

from __future__ import annotations

import math

from ..geo import GeoPoint, distance_m, north_east_m
from .state import SimState


class SimMotion(SimState):
    """Movement of the simulated vehicle in each time step."""

    def _move(self, dt: float) -> None:
        name = self.mode_name
        self.vn = self.ve = self.vd = 0.0
        if self.model == "copter":
            if name == "GUIDED":
                if self.takeoff_alt is not None:
                    self._climb_to(self.takeoff_alt, dt)
                    if self.alt >= self.takeoff_alt - 0.05:
                        self.takeoff_alt = None
                        self.guided_target = GeoPoint(
                            self.position.lat, self.position.lon, self.alt
                        )
                elif self.guided_target is not None and not self.landed:
                    self._fly_to(self.guided_target, dt)
            elif name == "LAND":
                self._descend(dt)
            elif name == "RTL":
                self._rtl(dt)
            if not self.landed:
                self._drift(dt)
        else:
            if name == "GUIDED" and self.guided_target is not None:
                self._drive_to(self.guided_target, dt)
            elif name == "RTL":
                home = GeoPoint(self.p.home.lat, self.p.home.lon, 0.0)
                self._drive_to(home, dt)

    def _drift(self, dt: float) -> None:
        """The part of the wind an airborne copter cannot lean against carries it."""
        wn, we = self.wind_ne
        speed = math.hypot(wn, we)
        if speed <= self.p.wind_limit:
            return
        excess = (speed - self.p.wind_limit) / speed
        self.north += wn * excess * dt
        self.east += we * excess * dt
        self.vn += wn * excess
        self.ve += we * excess

    def _climb_to(self, alt: float, dt: float) -> None:
        rate = self.p.climb_rate if alt > self.alt else -self.p.descent_rate
        step = rate * dt
        if abs(alt - self.alt) <= abs(step):
            self.alt = alt
        else:
            self.alt += step
            self.vd = -rate
        self.landed = False

    def _fly_to(self, target: GeoPoint, dt: float) -> None:
        self._horizontal(target, dt)
        if abs(target.alt - self.alt) > 1e-3:
            self._climb_to(max(target.alt, 0.0), dt)

    def _drive_to(self, target: GeoPoint, dt: float) -> None:
        self._horizontal(target, dt)

    def _horizontal(self, target: GeoPoint, dt: float) -> None:
        tn, te = north_east_m(self.p.home, target)
        dn, de = tn - self.north, te - self.east
        dist = math.hypot(dn, de)
        if dist < 1e-3:
            return
        step = self.p.cruise_speed * dt
        self.heading = math.degrees(math.atan2(de, dn)) % 360.0
        if dist <= step:
            self.north, self.east = tn, te
        else:
            self.north += dn / dist * step
            self.east += de / dist * step
            self.vn = dn / dist * self.p.cruise_speed
            self.ve = de / dist * self.p.cruise_speed

    def _descend(self, dt: float) -> None:
        if self.landed:
            return
        rate = self.p.descent_rate if self.alt > 10 else self.p.land_speed
        self.alt = max(0.0, self.alt - rate * dt)
        self.vd = rate
        if self.alt <= 0.0:
            self.landed = True
            self.vd = 0.0
            self._disarm("Land complete, disarming")

    def _rtl(self, dt: float) -> None:
        if self.landed:
            return
        home = GeoPoint(self.p.home.lat, self.p.home.lon, max(self.alt, self.p.rtl_alt))
        if self.rtl_phase == "climb":
            if self.alt < self.p.rtl_alt - 0.05:
                self._climb_to(self.p.rtl_alt, dt)
                return
            self.rtl_phase = "return"
        if self.rtl_phase == "return":
            if distance_m(self.position, home) > 0.5:
                self._horizontal(home, dt)
                return
            self.rtl_phase = "land"
        self._descend(dt)
