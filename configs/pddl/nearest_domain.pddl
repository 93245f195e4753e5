; Places to visit by whichever vehicle is nearest: the planner does not assign them.
; (visit ?l) names no vehicle, so every vehicle's performer bids for it and the
; executor's best-bid auction gives each visit to the lowest bid, the MAVLink
; performer's distance to the place. The ground station records one visit's video
; at a time (downlink_free), so the visits are auctioned one after another and each
; auction sees every idle vehicle's bid. Once every place is visited, each vehicle
; parks (a copter lands, a rover stops and disarms).
(define (domain mavlink_nearest)
  (:requirements :strips :typing :negative-preconditions :universal-preconditions
                 :durative-actions)
  (:types vehicle location - object)
  (:predicates
    (visited ?l - location)
    (parked ?v - vehicle)
    (downlink_free))

  (:durative-action visit
    :parameters (?l - location)
    :duration (= ?duration 10)
    :condition (and (at start (not (visited ?l)))
                    (at start (downlink_free)))
    :effect (and (at start (not (downlink_free)))
                 (at end (downlink_free))
                 (at end (visited ?l))))

  (:durative-action park
    :parameters (?v - vehicle)
    :duration (= ?duration 10)
    :condition (at start (forall (?l - location) (visited ?l)))
    :effect (at end (parked ?v)))
)
