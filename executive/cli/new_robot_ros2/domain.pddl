; What the robot ROBOT_NAME can do: localize itself, then drive between places. Each
; durative action is carried out by the behavior robot.yaml's `tasks` names: move_to by a
; ROS 2 action (nav2_msgs/NavigateToPose), localize by a ROS 2 service (std_srvs/Trigger).
(define (domain ROBOT_NAME)
  (:requirements :strips :typing :durative-actions)

  ; A small type hierarchy: rooms and docks are places. The robot localizes only at a
  ; dock (where the map has its landmarks) and drives to any place.
  (:types room dock - place
          place - object)

  (:predicates
    (robot_at ?p - place)          ; where the robot is
    (visited ?p - place)           ; the robot has been there
    (localized))                   ; the robot knows where it is on the map

  ; Relocalize on the map at a dock (service /odometry/reset).
  (:durative-action localize
    :parameters (?d - dock)
    :duration (= ?duration 1)
    :condition (at start (robot_at ?d))
    :effect (at end (localized)))

  ; Drive to a place (action /navigate_to_pose, the goal pose from the place's pose).
  (:durative-action move_to
    :parameters (?from ?to - place)
    :duration (= ?duration 5)
    :condition (and
      (at start (robot_at ?from))
      (at start (localized)))
    :effect (and
      (at start (not (robot_at ?from)))
      (at end (robot_at ?to))
      (at end (visited ?to))))
)
