; The copter alone surveys two fields and lands back on its pad.
(define (problem mavlink_copter_survey)
  (:domain mavlink_drones)
  (:objects
    uav1 - copter
    pad north_field east_field - location)
  (:init
    (at uav1 pad)
    (landed uav1)
    (= (battery uav1) 100))
  (:goal (and
    (surveyed north_field)
    (surveyed east_field)
    (at uav1 pad)
    (landed uav1)))
)
