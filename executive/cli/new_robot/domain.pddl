; What the robot ROBOT_NAME can do. Each durative action is carried out by the behavior
; the robot description's `tasks` names. Add an action here and a task (and a behavior)
; there; `dura validate robot.yaml` checks that they fit.
(define (domain ROBOT_NAME)
  (:requirements :strips :typing :durative-actions)

  ; A small type hierarchy: rooms and docks are places. An action on a place takes
  ; either; `inspect` takes rooms only.
  (:types room dock - place
          place - object)

  (:predicates
    (robot_at ?p - place)          ; where the robot is
    (connected ?from ?to - place)  ; a path the robot can drive
    (inspected ?r - room))         ; the room was inspected

  ; Drive from one place to another along a path (behavior drive).
  (:durative-action drive
    :parameters (?from ?to - place)
    :duration (= ?duration 4)
    :condition (and
      (at start (robot_at ?from))
      (over all (connected ?from ?to)))
    :effect (and
      (at start (not (robot_at ?from)))
      (at end (robot_at ?to))))

  ; Look at a room where the robot stands (behavior inspect).
  (:durative-action inspect
    :parameters (?r - room)
    :duration (= ?duration 2)
    :condition (over all (robot_at ?r))
    :effect (at end (inspected ?r)))
)
