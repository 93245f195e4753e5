; Mobile bases driving between named places; used by the CAN mission
; (configs/can_base.yaml). A move may only run while the robot's battery is not
; low: the CAN performer writes (battery ?r) and (battery_low ?r) from the base's
; status frame, so a battery dropping below the threshold halts the move.
(define (domain mobile_base)
  (:requirements :strips :typing :durative-actions :numeric-fluents :negative-preconditions)
  (:types robot location)
  (:predicates
    (robot_at ?r - robot ?l - location)
    (visited ?r - robot ?l - location)
    (battery_low ?r - robot))
  (:functions
    (travel_time ?from ?to - location)
    (battery ?r - robot))
  (:durative-action move
    :parameters (?r - robot ?from ?to - location)
    :duration (= ?duration (travel_time ?from ?to))
    :condition (and
      (at start (robot_at ?r ?from))
      (over all (not (battery_low ?r))))
    :effect (and
      (at start (not (robot_at ?r ?from)))
      (at end (robot_at ?r ?to))
      (at end (visited ?r ?to))))
)
