; The rover alone inspects the gate and the east field and drives back to its yard.
(define (problem mavlink_rover_patrol)
  (:domain mavlink_drones)
  (:objects
    ugv1 - rover
    yard gate east_field - location)
  (:init
    (at ugv1 yard)
    (= (battery ugv1) 100))
  (:goal (and
    (inspected gate)
    (inspected east_field)
    (at ugv1 yard)))
)
