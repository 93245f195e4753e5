; A robot moving between the rooms of a flat; used by the bag replay mission
; (configs/rosbag_replay.yaml). Move durations come from travel_time, set to the
; recorded durations of the bag segments; robot_x / robot_y follow the replayed pose.
(define (domain flat_navigation)
  (:requirements :strips :typing :durative-actions :fluents)
  (:types robot room)
  (:predicates
    (robot_at ?r - robot ?room - room)
    (connected ?from ?to - room)
    (visited ?r - robot ?room - room))
  (:functions
    (travel_time ?from ?to - room)
    (robot_x ?r - robot)
    (robot_y ?r - robot))
  (:durative-action move
    :parameters (?r - robot ?from ?to - room)
    :duration (= ?duration (travel_time ?from ?to))
    :condition (and
      (at start (robot_at ?r ?from))
      (over all (connected ?from ?to)))
    :effect (and
      (at start (not (robot_at ?r ?from)))
      (at end (robot_at ?r ?to))
      (at end (visited ?r ?to))))
)
