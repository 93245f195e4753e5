; Two bases that can each serve a place; a base whose battery is sensed low must
; not drive (over all), so a low battery mid-move halts it and the other base is
; sent instead. Used by tests/sensing (sensing rules on the CAN base double).
(define (domain sensing_bases)
  (:requirements :strips :typing :durative-actions :numeric-fluents :negative-preconditions)
  (:types robot location)
  (:predicates
    (robot_at ?r - robot ?l - location)
    (served ?l - location)
    (battery_low ?r - robot))
  (:functions
    (travel_time ?r - robot ?to - location)
    (battery_level ?r - robot))
  (:durative-action move
    :parameters (?r - robot ?from ?to - location)
    :duration (= ?duration (travel_time ?r ?to))
    :condition (and
      (at start (robot_at ?r ?from))
      (over all (not (battery_low ?r))))
    :effect (and
      (at start (not (robot_at ?r ?from)))
      (at end (robot_at ?r ?to))
      (at end (served ?to))))
)
