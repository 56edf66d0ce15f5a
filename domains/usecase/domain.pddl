; The thesis use case (chapter 7): a mobile robot that drives between places and
; takes pictures. Each durative action is carried out by a behavior of the robot
; (see examples/usecase/robot.yaml, section `tasks`).
(define (domain usecase)
  (:requirements :strips :typing :durative-actions :numeric-fluents)
  (:types place)

  (:predicates
    (robot_at ?p - place)          ; where the robot is
    (connected ?from ?to - place)  ; a path the robot can drive
    (picture_taken ?p - place)     ; a picture of the place is stored
    (photographable ?p - place))   ; the place has something to photograph

  (:functions
    (travel_time ?from ?to - place)) ; seconds the robot needs for a path

  ; Drive from one place to another along a known path (behavior move_to).
  (:durative-action move_to
    :parameters (?from ?to - place)
    :duration (= ?duration (travel_time ?from ?to))
    :condition (and
      (at start (robot_at ?from))
      (over all (connected ?from ?to)))
    :effect (and
      (at start (not (robot_at ?from)))
      (at end (robot_at ?to))))

  ; Take a picture where the robot stands (behavior take_picture).
  (:durative-action take_picture
    :parameters (?p - place)
    :duration (= ?duration 2)
    :condition (and
      (over all (robot_at ?p))
      (at start (photographable ?p)))
    :effect (at end (picture_taken ?p)))
)
