; The use-case world with a goal, for `dura plan --offline`: pictures of the lab and
; the office, and back to the dock.
(define (problem usecase-pictures) (:domain usecase)
  (:objects dock lab office - place)
  (:init
    (robot_at dock)
    (connected dock lab) (connected lab dock)
    (connected lab office) (connected office lab)
    (connected office dock) (connected dock office)
    (photographable lab) (photographable office)
    (= (travel_time dock lab) 4) (= (travel_time lab dock) 4)
    (= (travel_time lab office) 3) (= (travel_time office lab) 3)
    (= (travel_time office dock) 5) (= (travel_time dock office) 5))
  (:goal (and (picture_taken lab) (picture_taken office) (robot_at dock))))
