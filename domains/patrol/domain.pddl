; A patrol robot whose drivers are ROS 2 nodes (examples/ros2): it localizes itself,
; then drives between places. move_to is a ROS 2 action (nav2_msgs/NavigateToPose),
; localize a ROS 2 service call (std_srvs/Trigger); see examples/ros2/robot.yaml.
(define (domain patrol)
  (:requirements :strips :typing :durative-actions :numeric-fluents)
  (:types place)

  (:predicates
    (robot_at ?p - place)          ; where the robot is
    (visited ?p - place)           ; the robot has been there
    (localized))                   ; the robot knows where it is on the map

  (:functions
    (travel_time ?from ?to - place)) ; seconds the navigator needs for a path

  ; Relocalize on the map where the robot stands (service /odometry/reset).
  (:durative-action localize
    :parameters (?p - place)
    :duration (= ?duration 1)
    :condition (at start (robot_at ?p))
    :effect (at end (localized)))

  ; Drive to a place (action /navigate_to_pose, the goal pose from the place's pose).
  (:durative-action move_to
    :parameters (?from ?to - place)
    :duration (= ?duration (travel_time ?from ?to))
    :condition (and
      (at start (robot_at ?from))
      (at start (localized)))
    :effect (and
      (at start (not (robot_at ?from)))
      (at end (robot_at ?to))
      (at end (visited ?to))))
)
