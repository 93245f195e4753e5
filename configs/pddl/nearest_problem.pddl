; Two copters and a rover, three places, each place near one vehicle's home.
(define (problem mavlink_nearest_three)
  (:domain mavlink_nearest)
  (:objects
    uav1 uav2 ugv1 - vehicle
    tower orchard gate - location)
  (:init (downlink_free))
  (:goal (and
    (visited tower)
    (visited orchard)
    (visited gate)
    (parked uav1)
    (parked uav2)
    (parked ugv1)))
)
