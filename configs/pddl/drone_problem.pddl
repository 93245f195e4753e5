; A copter surveys two fields and a rover inspects the gate; both come back home.
(define (problem mavlink_survey)
  (:domain mavlink_drones)
  (:objects
    uav1 - copter
    ugv1 - rover
    pad yard north_field east_field gate - location)
  (:init
    (at uav1 pad)
    (landed uav1)
    (at ugv1 yard)
    (= (battery uav1) 100)
    (= (battery ugv1) 100))
  (:goal (and
    (surveyed north_field)
    (surveyed east_field)
    (inspected gate)
    (at uav1 pad)
    (landed uav1)
    (at ugv1 yard)))
)
