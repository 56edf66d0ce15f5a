; The world ROBOT_NAME starts in: a dock and two rooms (their poses are under `objects:`
; in robot.yaml). Goals come at run time (`dura goal add`).
(define (problem ROBOT_NAME-world) (:domain ROBOT_NAME)
  (:objects
    base - dock
    lab office - room)
  (:init
    (robot_at base))
  (:goal (and)))
