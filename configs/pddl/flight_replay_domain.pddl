; A copter surveying and coming home, for re-running recorded flights offline
; (configs/flight_replay.yaml). (battery_low ?c) comes from sensing rules on the
; vehicle's BATTERY_STATUS: it stops flights (over all), so a low battery halts the
; flight under way and the planner sends the copter home with rtl, which a low
; battery does not forbid (ArduPilot's battery failsafe does the same). (free ?c):
; one manoeuvre at a time.
(define (domain flight_replay)
  (:requirements :strips :typing :negative-preconditions :durative-actions :numeric-fluents)
  (:types copter location)
  (:predicates
    (at ?c - copter ?l - location)
    (home ?c - copter ?l - location)
    (landed ?c - copter)
    (airborne ?c - copter)
    (surveyed ?l - location)
    (battery_low ?c - copter)
    (free ?c - copter))
  (:functions
    (battery ?c - copter))

  (:durative-action takeoff
    :parameters (?c - copter ?l - location)
    :duration (= ?duration 10)
    :condition (and (at start (landed ?c)) (at start (free ?c)) (over all (at ?c ?l)))
    :effect (and (at start (not (landed ?c))) (at start (not (free ?c)))
                 (at end (airborne ?c)) (at end (free ?c))))

  (:durative-action fly
    :parameters (?c - copter ?from - location ?to - location)
    :duration (= ?duration 30)
    :condition (and (at start (at ?c ?from))
                    (at start (free ?c))
                    (over all (airborne ?c))
                    (over all (not (battery_low ?c))))
    :effect (and (at start (not (at ?c ?from)))
                 (at start (not (free ?c)))
                 (at end (at ?c ?to))
                 (at end (surveyed ?to))
                 (at end (free ?c))))

  (:durative-action rtl
    :parameters (?c - copter ?h - location)
    :duration (= ?duration 40)
    :condition (and (at start (home ?c ?h)) (at start (free ?c)) (over all (airborne ?c)))
    :effect (and (at start (not (free ?c)))
                 (at start (forall (?l - location) (not (at ?c ?l))))
                 (at end (at ?c ?h))
                 (at end (free ?c))))

  (:durative-action land
    :parameters (?c - copter ?l - location)
    :duration (= ?duration 15)
    :condition (and (at start (airborne ?c)) (at start (free ?c)) (over all (at ?c ?l)))
    :effect (and (at start (not (airborne ?c))) (at start (not (free ?c)))
                 (at end (landed ?c)) (at end (free ?c))))
)
