; The world ROBOT_NAME starts in: a dock and two rooms. Put your robot's places here,
; and the paths between them. Goals come at run time (`dura goal add`).
(define (problem ROBOT_NAME-world) (:domain ROBOT_NAME)
  (:objects
    base - dock
    kitchen hall - room)
  (:init
    (robot_at base)
    (connected base hall) (connected hall base)
    (connected hall kitchen) (connected kitchen hall))
  (:goal (and)))
