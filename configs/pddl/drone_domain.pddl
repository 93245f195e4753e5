; Copters and rovers visiting places: the MAVLink adapter's demo domain.
; A copter takes off, surveys locations from the air and lands; a rover drives
; to locations to inspect them.
; Durations are rough times at the vehicle double's default speeds.
; (battery_low ?v) comes from the vehicle's telemetry: it stops flights and drives
; (over all), so the executor halts them and replans, landing where it can.
(define (domain mavlink_drones)
  (:requirements :strips :typing :negative-preconditions :durative-actions :numeric-fluents)
  (:types
    vehicle location - object
    copter rover - vehicle)
  (:predicates
    (at ?v - vehicle ?l - location)
    (landed ?c - copter)
    (airborne ?c - copter)
    (surveyed ?l - location)
    (inspected ?l - location)
    (battery_low ?v - vehicle))
  (:functions
    (battery ?v - vehicle))

  (:durative-action takeoff
    :parameters (?c - copter ?l - location)
    :duration (= ?duration 5)
    :condition (and (at start (landed ?c))
                    (over all (at ?c ?l)))
    :effect (and (at start (not (landed ?c)))
                 (at end (airborne ?c))))

  (:durative-action fly
    :parameters (?c - copter ?from - location ?to - location)
    :duration (= ?duration 10)
    :condition (and (at start (at ?c ?from))
                    (over all (airborne ?c))
                    (over all (not (battery_low ?c))))
    :effect (and (at start (not (at ?c ?from)))
                 (at end (at ?c ?to))
                 (at end (surveyed ?to))))

  (:durative-action land
    :parameters (?c - copter ?l - location)
    :duration (= ?duration 8)
    :condition (and (at start (airborne ?c))
                    (over all (at ?c ?l)))
    :effect (and (at start (not (airborne ?c)))
                 (at end (landed ?c))))

  (:durative-action drive
    :parameters (?r - rover ?from - location ?to - location)
    :duration (= ?duration 15)
    :condition (and (at start (at ?r ?from))
                    (over all (not (battery_low ?r))))
    :effect (and (at start (not (at ?r ?from)))
                 (at end (at ?r ?to))
                 (at end (inspected ?to))))
)
